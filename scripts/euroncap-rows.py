#!/usr/bin/env python3
"""Rewrite docs/euroncap.md's sheet tables (between its `euroncap-rows:start/end` markers).

    .venv/bin/python scripts/euroncap-rows.py [--check]

The tables come from `roadgaze.conformance.dossier_rows` (the same table the dossier is filled
from) with the default configuration's settings. `--check` only says whether the page is up to
date (exit 1 when not).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from roadgaze.config import Config
from roadgaze.conformance.dossier_report import DOC_END, DOC_START, doc_block

PAGE = Path(__file__).resolve().parents[1] / "docs" / "euroncap.md"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare only, write nothing")
    args = parser.parse_args()
    text = PAGE.read_text(encoding="utf-8")
    start, end = text.find(DOC_START), text.find(DOC_END)
    if start < 0 or end < start:
        raise SystemExit(f"euroncap-rows: {PAGE} has no {DOC_START} ... {DOC_END} block")
    new = text[:start] + doc_block(Config().monitor) + text[end + len(DOC_END) :]
    if args.check:
        print("up to date" if new == text else f"{PAGE} differs from the table")
        return 0 if new == text else 1
    PAGE.write_text(new, encoding="utf-8")
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
