"""Command line: ``rotor-bridge run|emulate|demo|check-config|ports``."""

from __future__ import annotations

import argparse
import importlib.util
import json
import logging
import os
import signal
import sys

from bridge import __version__
from bridge.core.ending import Ending
from bridge.core.text import shown_path
from bridge.settings import ConfigError, Settings, load_settings

EXIT_CONFIG = 2
ERROR_LINE_MAX = 1000  # _fail: the most of one line of a configuration error printed
STOPPED_EARLY = "stopped before it started"  # Ctrl-C before a command's own handling (main)


def _setup_logging(level: str) -> None:
    logging.basicConfig(
        level=level,
        format="%(asctime)s %(levelname)-7s %(name)s: %(message)s",
        stream=sys.stderr,
    )


def _load(args: argparse.Namespace) -> Settings:
    try:
        return load_settings(args.config)
    except ConfigError as exc:
        raise _fail(exc) from None


def _fail(exc: ConfigError) -> SystemExit:
    """The error in one line per problem, each cut short (ERROR_LINE_MAX): a validator may
    quote the value it refuses, and an attack pass gave mqtt.host 70,000 characters: check-config
    printed them whole, twice for a state_file as long (the terminal, the journal)."""
    lines = []
    head, tail = ERROR_LINE_MAX * 2 // 3, ERROR_LINE_MAX // 3  # (the reason is at the end)
    for line in f"rotor-bridge: {exc}".splitlines():
        if len(line) > ERROR_LINE_MAX:
            cut = len(line) - head - tail
            line = f"{line[:head]} ...({cut} characters not shown)... {line[-tail:]}"
        lines.append(line)
    print("\n".join(lines), file=sys.stderr)
    return SystemExit(getattr(exc, "exit_code", EXIT_CONFIG))  # app.NotYet: 1, to be retried


def cmd_run(args: argparse.Namespace) -> int:
    from bridge.app import run

    settings = _load(args)
    _setup_logging(args.log_level or settings.log_level)
    logging.getLogger(__name__).info(
        "rotor-bridge %s starting with %d rotator(s)", __version__, len(settings.rotators)
    )
    if settings._service_links:  # (settings/config.py rule 9)
        logging.getLogger(__name__).info(
            "ignored %s: set by Kubernetes for a Service named rotor-bridge, no keys",
            ", ".join(settings._service_links),
        )
    try:
        return run(settings)
    except ConfigError as exc:  # the start failed (a port taken, a directory not writable)
        raise _fail(exc) from None


def cmd_check_config(args: argparse.Namespace) -> int:
    """A summary, the warnings, every value with --full, and the line that says it is good
    (settings/report.py); a file that is not good is one message on stderr and exit 2."""
    from bridge.feature import check_feature, registered
    from bridge.settings.report import check_state_file, config_warnings, masked, summary

    settings = _load(args)
    warnings: list[str] = []
    try:
        check_state_file(settings)  # as the start tries it (settings/report.py rule 5)
        for feature in registered():  # a feature's files, as its start reads them
            warnings += check_feature(feature, settings)  # (and what that start warns of)
    except ConfigError as exc:
        raise _fail(exc) from None
    for line in summary(settings):
        print(line)
    warnings = config_warnings(settings) + warnings
    for warning in warnings:
        print(f"warning: {warning}")
    if args.full:
        print("every value (model defaults filled in):")
        print(json.dumps(masked(settings), indent=2))
    path = args.config or os.environ.get("ROTOR_BRIDGE_CONFIG")
    source = shown_path(os.path.abspath(path)) if path else "(the environment)"
    print(f"config OK: {source}")
    return 0


def cmd_ports(args: argparse.Namespace) -> int:
    from bridge.runtime.port import list_serial_ports

    ports = list_serial_ports()
    if not ports:
        print("no serial ports found (is the USB adapter plugged in?)")
        return 0
    for p in ports:
        print(shown_path(p.device))
        stable = p.stable_path or p.device + "  (no /dev/serial/by-id link)"
        print(f"  use this path: {shown_path(stable)}")
        if p.description and p.description != "n/a":
            print(f"  description:   {p.description}")
        if p.vid is not None:
            print(f"  usb id:        {p.vid:04x}:{p.pid:04x} serial {p.serial_number or '-'}")
    return 0


def cmd_emulate(args: argparse.Namespace) -> int:
    from bridge.emulators import cli as emulate_cli

    _setup_logging(args.log_level or "WARNING")
    return emulate_cli.run(args)


def cmd_demo(args: argparse.Namespace) -> int:
    from bridge import demo

    _setup_logging(args.log_level or "INFO")
    return demo.run(args)


def cmd_remote(args: argparse.Namespace) -> int:
    """Ctrl-C or SIGTERM from its first step on ends the start as a start error (remote/run.py
    rule 1): its modules are loaded, its file read, with the signals already its own."""
    stopping = Ending()
    try:
        with stopping.on_signals(signal.SIGINT, signal.SIGTERM):
            from bridge.remote.run import run
            from bridge.remote.settings import load_remote_settings

            try:
                settings = load_remote_settings(args.config)
            except ConfigError as exc:
                raise _fail(exc) from None
            _setup_logging(args.log_level or "INFO")
            from bridge.settings.web import web_warnings

            for warning in web_warnings(settings.web):  # (settings/report.py rule 3)
                logging.getLogger(__name__).warning("%s", warning)
            try:
                return run(settings, stopping)
            except (ConfigError, OSError) as exc:  # no such rotator, no broker, a port taken
                print(f"rotor-bridge remote: {exc}", file=sys.stderr)
                raise SystemExit(EXIT_CONFIG) from None
    finally:
        stopping.close()


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """``argv``: the command line to be parsed. The options of ``emulate`` and ``demo`` come
    from their modules (the emulators, the demo's console), which a start of ``run`` has no
    use for (a tenth of its start-up CPU): they are loaded only when ``argv`` names one of the
    two, or is None (every option, for the docs)."""
    parser = argparse.ArgumentParser(
        prog="rotor-bridge", description="Antenna rotator controllers on MQTT."
    )
    parser.add_argument("--version", action="version", version=f"rotor-bridge {__version__}")
    parser.add_argument(
        "--log-level",
        choices=["DEBUG", "INFO", "WARNING", "ERROR"],
        help="what the log on stderr shows (default: the file's log_level for run, INFO for "
        "demo and remote, WARNING for emulate)",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser(
        "run",
        help="run the bridge service",
        description="Run the bridge: open the serial ports, connect to the MQTT broker, serve "
        "the rotctld ports, until SIGTERM or Ctrl-C. A configuration or start-up error ends it "
        "with one message and exit code 2.",
    )
    p.add_argument("-c", "--config", help="TOML file (default: $ROTOR_BRIDGE_CONFIG)")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser(
        "check-config",
        help="validate the configuration and summarise it",
        description="Validate the configuration and summarise it: each rotator's model and "
        "whether its port is there, the broker, and what is on. Things that are allowed but "
        "probably wrong are warned about in the same output; --full adds every value the "
        "bridge would use, model defaults filled in, secrets masked. Exit code 0, with a last "
        "line 'config OK: FILE', when valid; 2 and one message on stderr when not.",
    )
    p.add_argument("-c", "--config", help="TOML file (default: $ROTOR_BRIDGE_CONFIG)")
    p.add_argument("--full", action="store_true", help="print every value as well")
    p.set_defaults(func=cmd_check_config)

    p = sub.add_parser(
        "ports",
        help="list serial ports with their stable names",
        description="List the serial ports with the stable /dev/serial/by-id/ name to put in "
        "a rotator's port setting (ttyUSB numbers change when adapters are re-plugged).",
    )
    p.set_defaults(func=cmd_ports)

    named = argv is None or not {"emulate", "demo"}.isdisjoint(argv)
    try:  # pseudo-terminals need a POSIX system; the remote (below) runs without one
        if named:
            from bridge import demo
            from bridge.emulators import cli as emulate_cli
        elif importlib.util.find_spec("termios") is None:
            raise ImportError("termios")
    except ImportError:
        pass  # Windows: no emulate and no demo
    else:
        p = sub.add_parser(
            "emulate",
            help="an emulated controller on a pseudo-terminal",
            description="Run an emulated rotator controller of MODEL on a pseudo-terminal and "
            "print its path, for trying the bridge, Hamlib's rotctl or other software without "
            "hardware.",
        )
        if named:
            emulate_cli.add_arguments(p)
        p.set_defaults(func=cmd_emulate)

        p = sub.add_parser(
            "demo",
            help="emulated rotators bridged to MQTT, no hardware needed",
            description="Emulated rotators bridged to MQTT: the broker at --mqtt-host:"
            "--mqtt-port is used, or a private mosquitto started there; type a bearing, s "
            "(stop) or lock on/off.",
        )
        if named:
            demo.add_arguments(p)
        p.set_defaults(func=cmd_demo)

    p = sub.add_parser(
        "remote",
        help="the station's rotators on this computer, through its MQTT broker",
        description="On the operator's computer: connect to the station's MQTT broker, learn "
        "the rotators named in the file from the station, and offer each on the local "
        "endpoints the file asks for (rotctld, GS-232, Easycomm, PstRotator UDP, the console), "
        "until SIGTERM or Ctrl-C. Commands are never queued while the broker is away.",
    )
    p.add_argument("-c", "--config", required=True, help="the remote's TOML file")
    p.set_defaults(func=cmd_remote)
    return parser


def main(argv: list[str] | None = None) -> int:
    """A Ctrl-C before a command has the signals (the bridge's, the remote's, the demo's and
    the emulators' take them once loaded; the remote's from its first step, cmd_remote) is one
    line and exit code 2, not a traceback: loading the bridge takes a few tenths of a second.
    A pipe that closes before check-config or ports has printed all (``| head``) ends it with
    exit code 1 and no traceback. What stdout cannot encode is escaped, as on stderr (_escaping).
    """
    argv = sys.argv[1:] if argv is None else argv
    _escaping(sys.stdout)
    who = "rotor-bridge"
    args = None
    try:
        args = build_parser(argv).parse_args(argv)
        if args.func is cmd_remote:
            who = "rotor-bridge remote"
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print(f"{who}: {STOPPED_EARLY}", file=sys.stderr)
        return EXIT_CONFIG
    except BrokenPipeError:
        if args is not None and args.func not in _PRINTERS:  # (None: --help printed)
            raise
        # `check-config | head`: the reader left; no traceback, and none at exit's flush either
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _escaping(stream: object) -> None:
    """``stream`` escapes, with a backslash, what its encoding cannot write, as Python's stderr
    does, where it raised: a path holds what the home folder's name or the configuration
    file's does (settings/base.py rules 3, 7), any bytes, which Python reads as lone
    surrogates, and under en_US.UTF-8 stdout refused one: check-config ended in a
    UnicodeEncodeError traceback (review 69). So a path reads the same in what check-config
    prints and in the log, under every locale (C.UTF-8's stdout wrote the raw byte)."""
    reconfigure = getattr(stream, "reconfigure", None)  # (a StringIO's has none: no encoding)
    if reconfigure is not None:
        reconfigure(errors="backslashreplace")


# the commands whose output is only printed, which a pipe may close early (main)
_PRINTERS = (cmd_check_config, cmd_ports)


if __name__ == "__main__":
    sys.exit(main())
