"""The ``vlref`` command line: every argument parser of vlref, one module per sub-command.

Exit codes: 0 success (``compare``: pass), 1 ``compare``/``golden verify`` failed, 2 bad input
(the message names the file, the field and the reason, and nothing is written), 130 / 143 interrupted
by SIGINT (Ctrl-C) / SIGTERM (one line ``vlref: interrupted``, nothing partial left behind).

* :mod:`.commands`      the sub-command table, :func:`main` (the ``vlref`` entry point), exit codes, signals
* :mod:`.options`       options shared by several commands; the scene they name, checked before any work
* :mod:`.progress_bar`  the stage/row progress bar of long commands
* :mod:`.render`, :mod:`.scenes`, :mod:`.reference`, :mod:`.bias`, :mod:`.sweep`, :mod:`.compare`,
  :mod:`.golden`, :mod:`.march`, :mod:`.march_export`, :mod:`.bench`, :mod:`.warmup`: one command each
"""

from .commands import COMMANDS, build_parser, main

__all__ = ["COMMANDS", "build_parser", "main"]
