"""The controller's options every command that runs one takes (--controller, --settings, --gains) and the settings
they name: one reading for the rig and the simulation."""

from __future__ import annotations

import argparse
import math

from mantaray.protocol import messages as m
from mantaray.protocol.codec import choices

GAINS_HELP = (
    "the gains of every PID the controller runs, as the firmware takes them (configure_pid: "
    "deg/m, deg/(m s), deg s/m, deg) on the rig and on every simulated plant alike; default the firmware's boot "
    "gains, the paper's (a simulated plant that reads the paper's gains per radian, such as paper, boots them "
    "180/pi times larger: leave --gains out to run the paper's controller there)"
)


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
    values, with --gains on each of its PIDs (where the command takes --gains); a --controller that contradicts the
    file, or --gains beside a file that sets gains, is a usage error. The controller is the settings' (args is
    left as parsed). The one shape every command carries a controller's gains in: the settings' pid.AXIS.NAME keys,
    the firmware's numbers."""
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
    if getattr(args, "gains", None) is None:
        return settings
    if any(k.startswith("pid.") for k, _ in settings.values):
        parser.error(f"--gains and {args.settings} both set the PIDs' gains: give them in one place")
    try:
        return settings.with_gains(args.gains)
    except SettingsError as exc:
        parser.error(f"--gains: {exc}")


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


def add_gains_argument(parser: argparse.ArgumentParser) -> None:
    """--gains, as every command that runs a controller on a firmware takes it (controller_settings() reads it)."""
    parser.add_argument("--gains", type=parse_gains, metavar="KP,KI,KD[,ILIM]", help=GAINS_HELP)
