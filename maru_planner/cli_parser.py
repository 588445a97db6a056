"""What the package's command lines share: a bad option is one line on stderr and exit code 2, never
argparse's usage block or a traceback; :class:`CliError` is a bad option value or output path."""

from __future__ import annotations

import argparse
from typing import NoReturn

from maru_planner.errors import InvalidRequest, one_line

EXIT_BAD_INPUT = 2


class CliError(InvalidRequest):
    """A bad command-line value or output path."""

    source = "cli"


class OneLineParser(argparse.ArgumentParser):
    """argparse whose errors are one line (the usage block is in --help) and exit with EXIT_BAD_INPUT."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {one_line(message)} (see --help)\n")
