"""Doctor check of the hand models (phone detection, `[hands]`)."""

from __future__ import annotations

from roadgaze.config import Config
from roadgaze.doctor.report import Check, Status


def check_hands(config: Config) -> list[Check]:
    """The configured hand models (and, with `[hands] body`, the pose models): verified in the
    cache and loaded by LiteRT (OK), missing or damaged (WARN: the service runs,
    phone detection is off), or `[hands]` switched off."""
    from roadgaze.errors import ModelError
    from roadgaze.landmarks.hands.models import find_hand_models, fix_hint, model_names
    from roadgaze.landmarks.model_store import default_cache_dir

    hands = config.hands
    if not hands.enabled:
        return [Check("hands", Status.OK, "phone detection is off ([hands] enabled = false)")]
    names: tuple[str, ...] = model_names(hands.models, hands.models)
    if hands.body:  # the upper body's models, provisioned with the hands'
        from roadgaze.landmarks.pose.models import DETECTOR_NAME, LANDMARKS_NAME

        names = (*names, DETECTOR_NAME, LANDMARKS_NAME)
    found, problems = find_hand_models(config.model, names)
    if problems:
        return [
            Check(
                "hands",
                Status.WARN,
                f"phone detection is off: {'; '.join(problems)}",
                fix_hint(default_cache_dir(config.model)),
            )
        ]
    try:
        from roadgaze.landmarks.hands.engine import HandLandmarker, HandSettings

        HandLandmarker(found[names[0]], found[names[1]], HandSettings()).close()
        if len(names) == 4:  # and the body's
            from roadgaze.landmarks.pose.engine import PoseLandmarker, PoseSettings

            PoseLandmarker(found[names[2]], found[names[3]], PoseSettings()).close()
    except (ImportError, ModelError) as exc:
        return [Check("hands", Status.WARN, f"phone detection is off: {exc}", "pip install "
                      "'ai-edge-litert==2.3.0' or roadgaze model fetch hands --force")]  # fmt: skip
    sizes = ", ".join(f"{path.name} ({path.stat().st_size:,} bytes)" for path in found.values())
    return [Check("hands", Status.OK, f"{sizes}: SHA-256 verified, LiteRT loads them")]
