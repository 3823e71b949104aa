"""Command-line entry point: `mantaray <command>`; run `mantaray --help` for the list."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path


class Parser(argparse.ArgumentParser):
    """argparse, but a value such as -0.05,0.05 (a point with a negative first coordinate) is a value, not an option.

    argparse takes only a plain negative number (-0.05) for a value; points X,Y are written with a comma, so
    `--target -0.05,0.05` would fail with "expected one argument". Subcommands get the same class."""

    NEGATIVE_VALUES = re.compile(r"^-\.?\d[\d.eE+-]*([, ]-?\.?\d[\d.eE+-]*)*$")

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = self.NEGATIVE_VALUES  # argparse's own hook for "looks like a number"


def cmd_vmcu(args: argparse.Namespace) -> int:
    """Start the virtual MCU on a pty, identify it, and keep it running until Ctrl-C or SIGTERM."""
    import signal
    import time

    from mantaray.host.link import Link
    from mantaray.host.transport import SerialTransport
    from mantaray.host.vmcu import VirtualMcu

    def stop(signum, frame):
        raise KeyboardInterrupt  # as Ctrl-C: the virtual MCU stops and its temporary folder goes

    signal.signal(signal.SIGTERM, stop)
    with VirtualMcu(clock=args.clock) as vmcu:
        link = Link(SerialTransport(vmcu.path))
        reply = link.identify()
        link.close()
        print(
            f"virtual MCU on {vmcu.path}: protocol {reply.protocol_version}, firmware "
            f"{reply.firmware_major}.{reply.firmware_minor}.{reply.firmware_patch}, "
            f"schema 0x{reply.schema_hash:08X} (matches this host), clock {reply.clock.name.lower()}"
        )
        if args.identify_only:
            return 0
        try:  # from the line that says so on, a stop is the normal end (exit 0)
            print("running; Ctrl-C stops it", flush=True)
            while vmcu.process.poll() is None:
                time.sleep(0.2)
        except KeyboardInterrupt:
            pass
    return 0


def cmd_conformance(args: argparse.Namespace, parser: argparse.ArgumentParser) -> int:
    """Run the protocol conformance suite against a firmware on a serial device path."""
    import pytest

    from mantaray.host.ports import PortError, check_port

    try:
        check_port(args.port)
    except PortError as exc:
        parser.error(str(exc))
    from mantaray.protocol import conformance

    pytest_args = [
        "--pyargs",
        "mantaray.protocol.conformance",
        f"--rootdir={Path(conformance.__file__).parent}",  # its tests named by module, not from the port's folder
        "-p",
        "mantaray.protocol.conformance.plugin",
        "-q",
        "-p",
        "no:cacheprovider",
    ]
    if args.port:
        pytest_args += ["--port", args.port]
    if args.rig:
        from mantaray.protocol.rig import rig_file

        try:
            rig_file(args.rig)  # what is wrong with it, in one line, before pytest starts
        except argparse.ArgumentTypeError as exc:
            parser.error(f"argument --rig: {exc}")
        pytest_args += ["--rig", args.rig]
    extra = args.pytest_args[1:] if args.pytest_args[:1] == ["--"] else args.pytest_args
    return int(pytest.main(pytest_args + extra))


SIM_HELP = "the MuJoCo rig with the firmware in the loop"  # `sim`'s line in `mantaray --help`


def _command(argv: list[str] | None) -> str | None:
    """The command a command line names: its first word that is not an option (None: none, as for --help)."""
    return next((word for word in (sys.argv[1:] if argv is None else argv) if not word.startswith("-")), None)


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The command line's parser. The simulation's commands are built only where argv names `sim` (or no command):
    building them loads the simulation's modules, which a rig's command never needs."""
    parser = Parser(prog="mantaray", description="MANTA-RAY control stack: firmware link, simulation and tools.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    vmcu = sub.add_parser(
        "vmcu", help="start the native virtual MCU on a pty and check the handshake", description=cmd_vmcu.__doc__
    )
    vmcu.add_argument(
        "--clock",
        choices=["wall", "sim"],
        default="wall",
        help="wall: real time (default); sim: time advances only by sim_clock messages",
    )
    vmcu.add_argument("--identify-only", action="store_true", help="exit after the handshake")
    vmcu.set_defaults(func=cmd_vmcu)

    conf = sub.add_parser(
        "conformance",
        help="run the protocol conformance suite against a firmware",
        description=cmd_conformance.__doc__ + " Without --port, a virtual MCU is started "
        "on a pty. Arguments after -- go to pytest.",
    )
    conf.add_argument("--port", help="serial device path of the firmware (board, simulator or pty)")
    conf.add_argument(
        "--rig",
        metavar="FILE",
        help="the rig file the firmware was built for (default protocol/rig.toml); without --port the virtual MCU "
        "started is that rig's build (protocol/rigs/array_2x2.toml: mantaray-vmcu-array_2x2)",
    )
    conf.add_argument(
        "pytest_args",
        nargs=argparse.REMAINDER,
        help="after --, options for pytest (e.g. -- -m 'not wall_timing' -k deadman)",
    )
    conf.set_defaults(func=lambda args: cmd_conformance(args, conf))

    from mantaray.host.cli import add_parsers as add_rig

    add_rig(sub)
    if _command(argv) in (None, "sim"):
        from mantaray.sim.cli.commands import add_parser as add_sim

        add_sim(sub, SIM_HELP)
    else:
        sub.add_parser("sim", help=SIM_HELP)  # listed; its options are built when it is the command
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 2
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print(f"mantaray {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a user-facing tool: one clear line, no traceback
        from mantaray.host.link import LinkError
        from mantaray.paths import NotBuilt

        expected = [LinkError, NotBuilt, OSError]
        simulation = sys.modules.get("mantaray.sim.model.model")  # only a command that loaded it can have failed in it
        if simulation is not None:  # (importing it here would load MuJoCo for the rig)
            expected.append(simulation.SimulationUnstable)
        if isinstance(exc, tuple(expected)):
            print(f"mantaray {args.command}: error: {exc}", file=sys.stderr)
            return 1
        raise


if __name__ == "__main__":
    sys.exit(main())
