"""The live view's options (--live, --live-port, --linger, --bind) and its server, as the rig and the simulation take
them; the viewer itself (host/view.py, Rerun) loads only when a run asks for it."""

from __future__ import annotations

import argparse

from mantaray.arguments import number


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
