"""Arguments the command lines share: a number within its bounds or PID gains, refused by argparse (exit 2) in one
line, and a controller's options (--controller, --settings) with the settings they name."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable

from mantaray.protocol import messages as m
from mantaray.protocol.codec import choices


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


def parse_gains(text: str) -> tuple[float, float, float, float]:
    """KP,KI,KD[,ILIMIT] of a PID [deg/m, deg/(m s), deg s/m, deg]; without ILIMIT the firmware's boot default."""
    try:
        values = tuple(float(v) for v in text.replace(",", " ").split())
    except ValueError:
        values = ()
    if len(values) == 3:
        values += (m.PID_DEFAULTS[m.Axis.X]["integral_limit"],)
    if len(values) != 4 or not all(math.isfinite(v) and v >= 0 for v in values):
        raise argparse.ArgumentTypeError(f"expected KP,KI,KD or KP,KI,KD,ILIMIT (numbers >= 0), got {text!r}")
    return values


def controller_settings(parser: argparse.ArgumentParser, args: argparse.Namespace):
    """The controller settings a command runs with: --settings FILE (its controller), else --controller's boot
    values; a --controller that contradicts the file is a usage error. Sets args.controller."""
    from mantaray.host.controller_settings import ControllerSettings, SettingsError

    try:
        settings = (
            ControllerSettings.load(args.settings)
            if args.settings
            else ControllerSettings(args.controller or "manhattan")
        )
    except SettingsError as exc:
        parser.error(str(exc))
    if args.controller and args.controller != settings.controller:
        parser.error(
            f"--controller {args.controller} contradicts {args.settings}, which sets up the "
            f"{settings.controller} controller"
        )
    args.controller = settings.controller
    if getattr(args, "gains", None) is not None and any(k.startswith("pid.") for k, _ in settings.values):
        parser.error(f"--gains and {args.settings} both set the PIDs' gains: give them in one place")
    return settings


def add_controller_arguments(parser: argparse.ArgumentParser) -> None:
    """--controller and --settings, as every command that runs a controller takes them."""
    parser.add_argument(
        "--controller",
        choices=choices(m.Controller),
        help="the tilt controller (default: manhattan, or the one --settings names)",
    )
    parser.add_argument(
        "--settings",
        metavar="FILE",
        help="a controller's settings (TOML, as mantaray sim tune writes: host/controller_settings.py)",
    )


def reporter(command: str) -> Callable[[str], None]:
    """What a command says on stderr while it works, each line named by the command (`mantaray COMMAND: ...`)."""

    def report(text: str) -> None:
        print(f"mantaray {command}: {text}", file=sys.stderr)

    return report


def add_view_arguments(parser: argparse.ArgumentParser) -> None:
    """--live, --live-port and --bind: the run's live view in a browser (host/view.py)."""
    from mantaray.host.view import DEFAULT_WEB_PORT, LOOPBACK

    parser.add_argument(
        "--live",
        action="store_true",
        help="watch the run live in the Rerun viewer, in a browser on this machine (the address is printed); "
        "the recording (.rrd) is written either way",
    )
    parser.add_argument(
        "--live-port",
        type=number(1024, 65534, integer=True),
        help=f"the live view's web page port; its data server takes the next one (default {DEFAULT_WEB_PORT})",
    )
    parser.add_argument(
        "--linger",
        type=number(0, 24 * 3600),
        metavar="SECONDS",
        help="keep the live view up this long after the run, for a browser opened late (default: from a terminal "
        "until Enter, else not at all)",
    )
    parser.add_argument(
        "--bind",
        metavar="ADDRESS",
        help=f"the address the live view listens on (default {LOOPBACK}: this machine only; 0.0.0.0 opens it to "
        "the network, with a warning)",
    )


def start_live(parser: argparse.ArgumentParser, args: argparse.Namespace, report):
    """The live view's server when --live asks for one (None otherwise); a port in use is a usage error."""
    from mantaray.host.view import DEFAULT_WEB_PORT, LOOPBACK, LiveOptions, LiveServer, ViewError

    if not args.live:
        given = [
            name
            for name, value in (("--live-port", args.live_port), ("--linger", args.linger), ("--bind", args.bind))
            if value is not None
        ]
        if given:
            parser.error(f"{', '.join(given)} set up the live view: add --live")
        return None
    try:
        return LiveServer(LiveOptions(args.bind or LOOPBACK, args.live_port or DEFAULT_WEB_PORT), report)
    except ViewError as exc:
        parser.error(str(exc))
