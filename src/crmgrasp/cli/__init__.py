"""The ``crmgrasp`` command: [`main`][] dispatches to one function per subcommand
([`crmgrasp.cli.main`][]); the argument parser lives in [`crmgrasp.cli.parser`][].
Subcommands import what they need when they run, so ``crmgrasp --help`` stays fast."""

from crmgrasp.cli.main import main

__all__ = ["main"]
