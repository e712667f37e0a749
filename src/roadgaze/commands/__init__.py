"""The `roadgaze` sub-commands, one module each, in the order `roadgaze --help` lists them."""

from types import ModuleType

from roadgaze.commands import (
    batch,
    bench,
    conformance,
    data,
    demo,
    doctor,
    estimate,
    evaluate,
    listen,
    model,
    paper,
    recover,
    replay,
    router,
    run,
    schema,
    security,
    speed,
    synth,
)

COMMANDS: tuple[ModuleType, ...] = (
    demo,
    run,
    listen,
    speed,
    router,
    replay,
    batch,
    conformance,
    recover,
    bench,
    evaluate,
    data,
    estimate,
    synth,
    model,
    schema,
    security,
    paper,
    doctor,
)
"""Each module has `register(subparsers)`, which adds its parser and sets `handler(args, config)`.
Heavy imports (MediaPipe, Zenoh, OpenCV) happen inside the handlers, so `--help` is fast."""

__all__ = ["COMMANDS"]
