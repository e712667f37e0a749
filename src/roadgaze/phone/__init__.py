"""Phone use from the record: hand and face features, the shipped classifier, the judgement."""

from roadgaze.phone.features import FEATURES, frame_vector
from roadgaze.phone.judge import judge
from roadgaze.phone.model import PhoneModel, load_model

__all__ = ["FEATURES", "PhoneModel", "frame_vector", "judge", "load_model"]
