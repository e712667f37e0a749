"""Conformance: scripted drives rendered with exact truth, run through the service, judged."""

from roadgaze.conformance.model import Outcome, Requirement, Scenario, Segment, judge

__all__ = ["Outcome", "Requirement", "Scenario", "Segment", "judge"]
