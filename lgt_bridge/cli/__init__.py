"""Command line: ``lgt-bridge demo | run | bench`` (one module per command).

Errors raised on purpose (:class:`~lgt_bridge.errors.LGTError` and subclasses, a missing
script, an unknown scene, a bad option value) print ``lgt-bridge: error: <message>`` on
stderr and exit with status 2; ``--debug`` shows their traceback. An error in a script
under ``run`` shows the script's own traceback (exit status 1); other unexpected
exceptions keep theirs.
"""
import argparse
import re
import sys

from ..errors import LGTError
from . import bench as _bench, demo as _demo, run as _run
from .options import Parser

_COMMANDS = {"demo": _demo, "run": _run, "bench": _bench}
# a value that starts like a negative number ("-1e-6", "-.5", "-inf"), which argparse would
# take for an option
_NEGATIVE = re.compile(r"^-(\d|\.\d|inf|nan)", re.IGNORECASE)


def _one_line(exc):
    return " ".join(str(exc).split()) or type(exc).__name__


def _parser():
    ap = argparse.ArgumentParser(prog="lgt-bridge", description="Lie group integration of "
                                 "absolute-coordinate multibody models (Exudyn, Pinocchio).")
    ap.add_argument("--debug", action="store_true", help="show the traceback of errors")
    sub = ap.add_subparsers(dest="cmd", parser_class=Parser)
    for cmd in _COMMANDS.values():
        cmd.add_parser(sub)
    return ap


def _value_options(ap):
    """The option strings (of every command) that take one value."""
    out = set()
    parsers = [ap] + [p for a in ap._actions if isinstance(a, argparse._SubParsersAction)
                      for p in a.choices.values()]
    for p in parsers:
        for a in p._actions:
            if a.option_strings and a.nargs is None:
                out.update(a.option_strings)
    return out


def _split_argv(argv, ap):
    """(the command line's own arguments, the script's arguments after ``--``), with a negative
    number given to an option joined to it (``--rtol -1e-6`` -> ``--rtol=-1e-6``), so that it
    reaches the option's own check instead of argparse's "expected one argument"."""
    argv = list(sys.argv[1:] if argv is None else argv)
    rest = []
    if "--" in argv:
        i = argv.index("--")
        argv, rest = argv[:i], argv[i + 1:]
    opts, out, i = _value_options(ap), [], 0
    while i < len(argv):
        if argv[i] in opts and i + 1 < len(argv) and _NEGATIVE.match(argv[i + 1]):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out, rest


def main(argv=None):
    ap = _parser()
    argv, rest = _split_argv(argv, ap)
    a = ap.parse_args(argv)
    if rest:
        if a.cmd != "run":
            ap.error(f"arguments after -- are the script's (lgt-bridge run SCRIPT -- ARGS); "
                     f"{a.cmd or 'no command'} takes none: {' '.join(rest)}")
        a.script_args = rest
    if a.cmd is None:
        a = ap.parse_args(["demo"])
    try:
        return _COMMANDS[a.cmd].run(a)
    except _run.ScriptFailed as exc:
        if a.debug:
            raise exc.exc
        sys.stderr.write(exc.text)
        return 1
    except LGTError as exc:
        if a.debug:
            raise
        print(f"lgt-bridge: error: {_one_line(exc)}", file=sys.stderr)
        return 2
