"""Bus options shared by the canfdi console commands, spelled like python-can's.

A test engineer who knows ``python -m can.logger -i socketcan -c vcan0`` should
find the same flags here (``-i/--interface``, ``-c/--channel``,
``-b/--bitrate``) and the same defaults: python-can's own configuration
(``~/.canrc`` / ``can.ini``, ``CAN_INTERFACE``, ``CAN_CHANNEL``), and where
that says nothing, SocketCAN on ``vcan0`` (the HIL bench's bus).

    p = argparse.ArgumentParser(); add_bus_args(p)
    a = p.parse_args()
    with open_bus(a) as bus: ...        # BusOpenError with a readable message
"""
from __future__ import annotations

import argparse
from typing import Any

import can
from can import util

FALLBACK_INTERFACE = "socketcan"
FALLBACK_CHANNEL = "vcan0"


class BusOpenError(RuntimeError):
    """The bus could not be opened; str() is one line a technician can act on."""


def config_defaults() -> tuple[str, str]:
    """(interface, channel) from python-can's configuration, else socketcan/vcan0.

    can.util.load_config() raises when no interface is configured anywhere, so
    the fallback is applied here rather than by passing a config dict (which
    would take precedence over the user's ~/.canrc and environment).
    """
    try:
        cfg: dict[str, Any] = dict(util.load_config())
    except (can.CanError, ValueError, OSError):
        try:
            cfg = dict(util.load_config(config={"interface": FALLBACK_INTERFACE}))
        except (can.CanError, ValueError, OSError):
            cfg = {}
    interface = str(cfg.get("interface") or FALLBACK_INTERFACE)
    channel = cfg.get("channel")
    return interface, str(channel) if channel not in (None, "") else FALLBACK_CHANNEL


def add_bus_args(parser: argparse.ArgumentParser) -> None:
    """Add -i/-c/-b with defaults shown in --help."""
    interface, channel = config_defaults()
    g = parser.add_argument_group("bus (python-can; defaults from ~/.canrc, CAN_INTERFACE, CAN_CHANNEL)")
    g.add_argument("-i", "--interface", default=interface,
                   help=f"python-can interface (default: {interface})")
    g.add_argument("-c", "--channel", default=channel,
                   help=f"channel, e.g. vcan0 (default: {channel})")
    g.add_argument("-b", "--bitrate", type=int, default=None,
                   help="bitrate in bit/s (ignored by socketcan/virtual)")


def open_bus(args: argparse.Namespace, **kwargs: Any) -> can.BusABC:
    """Open the bus named by add_bus_args' options; BusOpenError on failure."""
    extra: dict[str, Any] = dict(kwargs)
    if args.bitrate is not None:
        extra["bitrate"] = args.bitrate
    try:
        return can.Bus(interface=args.interface, channel=args.channel, **extra)
    except (can.CanError, OSError, ValueError, ImportError) as e:
        hint = ""
        if args.interface == "socketcan":
            hint = f" — no {args.channel} here? run under tools/vcan-run"
        raise BusOpenError(f"cannot open {args.interface} channel {args.channel}: {e}{hint}") from e
