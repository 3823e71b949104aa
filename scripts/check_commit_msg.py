#!/usr/bin/env python3
"""Checks a commit message's subject: `area: summary`, at most 72 characters (the pre-commit commit-msg hook).

Run: python3 scripts/check_commit_msg.py MESSAGE_FILE   (exit 0: it holds; 1: it does not, with one line saying why)
The area is one or more lower-case names of what the commit touches (`sim`, `firmware`, `docs`, `sim, host`).
Git's own comment lines (#) and merge and revert subjects are left alone.
"""

from __future__ import annotations

import re
import sys

MAX_SUBJECT = 72  # [characters] what `git log --oneline` and mail clients show whole
SUBJECT = re.compile(r"[a-z0-9][a-z0-9_.\-/]*(, [a-z0-9][a-z0-9_.\-/]*)*: \S")


def problem(message: str) -> str | None:
    """Why the message's subject does not hold (None: it holds)."""
    lines = [line for line in message.splitlines() if not line.startswith("#")]
    subject = next((line for line in lines if line.strip()), "")
    if subject.startswith(("Merge ", "Revert ")):
        return None
    if not SUBJECT.match(subject):
        return f"the subject {subject!r} is not `area: summary` (e.g. `sim: the reference becomes 0.5 ms`)"
    if len(subject) > MAX_SUBJECT:
        return f"the subject is {len(subject)} characters; at most {MAX_SUBJECT}: put the rest in the body"
    return None


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: check_commit_msg.py MESSAGE_FILE", file=sys.stderr)
        return 2
    with open(argv[1], encoding="utf-8", errors="replace") as f:
        why = problem(f.read())
    if why:
        print(f"commit message: {why}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
