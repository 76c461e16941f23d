"""The one error type for bad input (scene files, CLI arguments, image files).

Every message names the file, the field and the reason, as ``FILE: key.path: reason``.
The CLI turns it into exit code 2.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad user input.

    Parameters
    ----------
    file : str
        The file the bad value came from (``"<command line>"`` for CLI arguments).
    path : str
        The dotted key path inside that file (``"lights[1].spot_angle"``), or ``""``.
    reason : str
        What is wrong, in words a user can act on.
    """

    def __init__(self, file: str, path: str, reason: str):
        self.file = str(file)
        self.path = path
        self.reason = reason
        where = f"{self.file}: {path}: " if path else f"{self.file}: "
        super().__init__(where + reason)
