"""The human-readable table of a `roadgaze bench` result (the JSON object `bench --json` prints)."""

from __future__ import annotations

from typing import Any


def format_result(result: dict[str, Any]) -> str:
    """The human-readable table of a bench result."""
    lines = [
        f"bench {result['source']}: {result['frames']} frames ({result['frames_timed']} timed)",
        f"{'stage':<10} {'median ms':>10} {'p99 ms':>10}",
    ]
    for stage, stats in result["stages"].items():
        lines.append(f"{stage:<10} {stats['median_ms']:>10.3f} {stats['p99_ms']:>10.3f}")
    lines.append(
        f"fps            {result['fps']:.1f} (after the warm-up: {result['pipeline_fps']})"
    )
    lines.append(f"overhead_ratio {result['overhead_ratio']:.3f}")
    if result["raw_mediapipe_fps"] is not None:
        raw = result["raw_mediapipe"]
        lines.append(
            f"raw MediaPipe  {result['raw_mediapipe_fps']:.1f} fps (passes "
            f"{', '.join(str(fps) for fps in raw['passes_fps'])}; median {raw['median_ms']} ms)"
        )
        lines.append(
            f"ratio_to_raw   {result['ratio_to_raw']} (per pass: "
            f"{', '.join(str(ratio) for ratio in raw['ratios'])})"
        )
        lines.append(
            f"cpu ms/frame   {result['cpu_ms_per_frame']} (raw {raw['cpu_ms_per_frame']}; "
            f"cpu_ratio_to_raw {raw['cpu_ratio_to_raw']})"
        )
        lines.append(f"median_ratio_to_raw {raw['median_ratio_to_raw']} (median frame times)")
    if "latency" in result:
        latency = result["latency"]
        lines.append(
            f"latency        p50 {latency['p50_ms']} ms, p99 {latency['p99_ms']} ms, max "
            f"{latency['max_ms']} ms ({latency['received']} of {latency['published']} received; "
            f"target p99 <= {latency['target_p99_ms']} ms: "
            f"{'met' if latency['meets_target'] else 'not met'})"
        )
        lines.append(
            f"  of which   to publish p50 {latency['to_publish_p50_ms']} / p99 "
            f"{latency['to_publish_p99_ms']} ms, Zenoh delivery p50 {latency['delivery_p50_ms']} / "
            f"p99 {latency['delivery_p99_ms']} ms"
        )
    if "recording" in result:
        from roadgaze.benchmark.recording import format_recording

        lines += format_recording(result["recording"])
    if "memory" in result:
        memory = result["memory"]
        lines.append(
            f"memory: start {memory['rss_start_mb']} MiB, baseline {memory['rss_baseline_mb']} "
            f"MiB, end {memory['rss_end_mb']} MiB, peak {memory['rss_peak_mb']} MiB, "
            f"growth {memory['rss_growth_mb']} MiB"
        )
    return "\n".join(lines)
