"""One TOML reader (vlref.tomlfile): the tomli fallback that python_requires >= 3.10 needs lives in one
place, and every TOML format reports a missing or broken file the same way."""

import re
from pathlib import Path

import pytest

from vlref.errors import InputError
from vlref.tomlfile import read_toml

PACKAGE = Path(__file__).resolve().parents[1] / "vlref"


def test_no_module_imports_tomllib_directly():
    """Python 3.10 has no tomllib: only vlref/tomlfile.py may name it (with the tomli fallback)."""
    offenders = [str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py")
                 if p.name != "tomlfile.py" and re.search(r"^\s*(import tomllib|from tomllib)", p.read_text(), re.M)]
    assert offenders == []


def test_reads_a_table(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text('width = 64\n[grid]\n"render.steps" = [4, 8]\n')
    assert read_toml(path, "sweep file") == {"width": 64, "grid": {"render.steps": [4, 8]}}


def test_missing_and_broken_files_name_the_file_and_the_reason(tmp_path):
    with pytest.raises(InputError) as info:
        read_toml(tmp_path / "nope.toml", "port manifest")
    assert str(info.value) == f"{tmp_path / 'nope.toml'}: port manifest not found"
    bad = tmp_path / "bad.toml"
    bad.write_text("width = = 3\n")
    with pytest.raises(InputError) as info:
        read_toml(bad, "suite file")
    assert str(info.value).startswith(f"{bad}: unreadable suite file (")
