"""What the commands share: the group and chart choices (from the registries), the method
check, the common options (--progress, --debug) and the parser class."""
import argparse

from .. import charts as _charts
from ..errors import InputError
from ..integrators import registry as _methods
from ..lgt import GROUPS as _lgt_groups

GROUPS = (*_lgt_groups, "auto")
CHARTS = (*_charts.NAMES, "auto")

DEBUG = dict(action="store_true", default=argparse.SUPPRESS, help="show the traceback of errors")
PROGRESS = dict(action=argparse.BooleanOptionalAction, default=None,
                help="progress bars on stderr (default: only for runs longer than about 1 s "
                     "when stderr is a terminal, never when CI is set or output is piped)")


def check_method(m, where):
    """InputError unless ``m`` names a method of the registry."""
    try:
        _methods.get(m)
    except InputError:
        raise InputError(f"{where}: unknown method {m!r}; use one of {_methods.choices_text()}.") from None


def kinds():
    """The method names by kind, for the help texts (from the registry)."""
    fixed = ", ".join(_methods.by(steps="fixed"))
    adaptive = ", ".join(_methods.by(steps="adaptive"))
    implicit = ", ".join(_methods.by(steps="adaptive", implicit=True))
    scipy = ", ".join(_methods.SCIPY)
    return fixed, adaptive, implicit, scipy


def charts_help():
    return ", ".join(f"{c.name} ({c.title})" for c in _charts.CHARTS.values())


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose epilog may be computed when help is shown (``epilog_fn``)."""

    epilog_fn = None

    def format_help(self):
        if self.epilog_fn is not None:
            self.epilog = self.epilog_fn()
        return super().format_help()
