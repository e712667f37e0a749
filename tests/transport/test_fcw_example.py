"""The FCW example (docs/examples/fcw_support.py) moves its warning time on forward support:
earlier while heightened, later on normal, earlier again when the support messages stop (link or
service down), and refuses another vehicle's."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import time
from types import ModuleType

from repo_paths import REPO, child_env
from roadgaze.config import ZenohConfig
from roadgaze.transport import Keys, SupportLevel, SupportMessage, ZenohLink
from zenoh_helpers import LineReader, endpoint, free_port, router, stop_process, wait_for

EXAMPLE = REPO / "docs" / "examples" / "fcw_support.py"


def example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("fcw_support", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def support(seq: int, level: str, vehicle_id: str = "car-42") -> SupportMessage:
    rule = "euroncap.support.forward" if level == "heightened" else "roadgaze.support.forward.clear"
    reason = "head in left_mirror" if level == "heightened" else "watching the road 2 s"
    forward = SupportLevel(level=level, rule=rule, reason=reason, since_s=3.4)  # type: ignore[arg-type]
    return SupportMessage(
        vehicle_id=vehicle_id, seq=seq, t_s=seq / 15, wall_time=0.0, frame=seq, forward=forward,
        lane=forward,
    )  # fmt: skip


def test_the_warning_time_follows_forward_support_and_fails_safe_when_stale() -> None:
    fcw = example()
    assert fcw.warning_ttc_s(None, 0.0) == (3.0, "no support message yet")
    assert fcw.warning_ttc_s(support(0, "normal"), 0.1)[0] == 2.1
    ttc_s, why = fcw.warning_ttc_s(support(0, "heightened"), 0.1)
    assert (ttc_s, why) == (3.0, "euroncap.support.forward: head in left_mirror, since 3.40 s")
    assert fcw.warning_ttc_s(support(0, "normal"), 0.6)[1].endswith("link or service down")


def test_the_example_follows_the_bus() -> None:
    port = free_port()
    config = ZenohConfig(vehicle_id="car-42", connect=[endpoint(port)])
    with router(port), ZenohLink(config, Keys.from_config(config)) as link:
        assert wait_for(lambda: link.status().connected, timeout_s=15.0)
        process = subprocess.Popen(
            [sys.executable, str(EXAMPLE), "car-42", endpoint(port), "8"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
        )  # fmt: skip
        try:
            reader = LineReader(process)
            first = reader.next(20.0)  # nothing heard yet: early
            seq = 0
            for level, count in (("normal", 15), ("heightened", 15), ("normal", 15)):
                for _ in range(count):
                    link.publish_support(support(seq, level))
                    link.publish_support(support(seq, "heightened", "car-9"))  # a forgery
                    seq += 1
                    time.sleep(1 / 15)
            lines = [reader.next(10.0) for _ in range(3)]
            lines.append(reader.next(10.0))  # the messages stopped: early again
            _, stderr = process.communicate(timeout=30)
        finally:
            stop_process(process)
    assert first == "FCW warns at TTC 3.0 s (no support message yet)"
    assert (
        lines[0] == "FCW warns at TTC 2.1 s (roadgaze.support.forward.clear: watching the road 2 s)"
    )
    assert lines[1].startswith("FCW warns at TTC 3.0 s (euroncap.support.forward: head in left_")
    assert lines[2].startswith("FCW warns at TTC 2.1 s")
    assert lines[3].startswith("FCW warns at TTC 3.0 s (no support message for 0.")
    assert lines[3].endswith("link or service down)")
    assert "refused a support message: vehicle 'car-9'" in stderr and "Traceback" not in stderr
