"""What every command line shares, of no layer: a number within its bounds, refused by argparse (exit 2) in one line,
and the lines a command says on stderr while it works."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable


def number(
    low: float | None = None, high: float | None = None, *, above: bool = False, integer: bool = False
) -> Callable[[str], float]:
    """A type for add_argument: a finite number (an integer with integer=True) with low <= x <= high (low < x with
    above=True); either bound may be None."""
    kind = int if integer else float

    def parse(text: str) -> float:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected {'an integer' if integer else 'a number'}, got {text!r}"
            ) from None
        below_low = low is not None and (value <= low if above else value < low)
        if not math.isfinite(value) or below_low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"must be {_span(low, high, above)}, got {text}")
        return value

    return parse


def _span(low: float | None, high: float | None, above: bool) -> str:
    if low is not None and high is not None:
        return f"{low:g}..{high:g}" if not above else f"> {low:g} and <= {high:g}"
    if low is not None:
        return f"> {low:g}" if above else f">= {low:g}"
    return f"<= {high:g}" if high is not None else "a finite number"


def reporter(command: str) -> Callable[[str], None]:
    """What a command says on stderr while it works, each line named by the command (`mantaray COMMAND: ...`)."""

    def report(text: str) -> None:
        print(f"mantaray {command}: {text}", file=sys.stderr)

    return report
