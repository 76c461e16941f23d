"""TOML files: one reader for every vlref file format written in TOML (scenes, suites, sweeps, port
manifests, presets).

Python 3.11+ has ``tomllib`` in the standard library; 3.10 (``python_requires >= 3.10``) uses its
backport ``tomli``, which setup.cfg installs there. Modules import ``loads`` and ``TOMLDecodeError``
from here, never ``tomllib`` directly.
"""

from __future__ import annotations

import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    from tomllib import TOMLDecodeError, loads
else:  # pragma: no cover - exercised on Python 3.10 only
    from tomli import TOMLDecodeError, loads

from .errors import InputError

__all__ = ["TOMLDecodeError", "loads", "read_toml"]


def read_toml(path, what: str) -> dict:
    """The table of the TOML file ``path``; :class:`InputError` ``(path, "", reason)`` if it is missing
    (``"<what> not found"``) or unreadable (``"unreadable <what> (<parser message>)"``)."""
    file = str(path)
    try:
        return loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(file, "", f"{what} not found") from None
    except (OSError, UnicodeDecodeError, TOMLDecodeError) as exc:
        raise InputError(file, "", f"unreadable {what} ({exc})") from None
