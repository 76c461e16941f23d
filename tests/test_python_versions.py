"""setup.cfg promises Python >= 3.10; CI runs 3.11 (no 3.10 interpreter installs here). What 3.10 would
reject is checked statically: its grammar, and the standard-library names that 3.11 added."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted(p for d in ("vlref", "tests", "ports", "benchmarks") for p in (ROOT / d).rglob("*.py"))
# standard-library names new in 3.11 (What's New in Python 3.11); tomllib has its fallback in vlref.tomlfile
NEW_IN_311 = re.compile(r"\b(typing\.Self|from typing import[^\n]*\b(Self|LiteralString|Never|assert_never|reveal_type)\b"
                        r"|enum\.StrEnum|StrEnum\b|datetime\.UTC\b|hashlib\.file_digest|contextlib\.chdir"
                        r"|asyncio\.TaskGroup|asyncio\.timeout\b|ExceptionGroup|BaseExceptionGroup)")


def test_the_sources_are_found():
    assert len(SOURCES) > 100 and ROOT / "vlref" / "tomlfile.py" in SOURCES


def test_every_source_parses_with_the_python_310_grammar():
    rejected = []
    for path in SOURCES:
        try:
            ast.parse(path.read_text(encoding="utf-8"), filename=str(path), feature_version=(3, 10))
        except SyntaxError as exc:
            rejected.append(f"{path.relative_to(ROOT)}:{exc.lineno}: {exc.msg}")
    assert rejected == []


def test_the_310_grammar_check_rejects_311_syntax():
    with pytest.raises(SyntaxError):
        ast.parse("try:\n    pass\nexcept* ValueError:\n    pass\n", feature_version=(3, 10))


def test_no_standard_library_name_added_in_311():
    code_lines = [(p, n, line) for p in SOURCES if p.name != Path(__file__).name
                  for n, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1)
                  if not line.lstrip().startswith("#")]
    offenders = [f"{p.relative_to(ROOT)}:{n}: {line.strip()}" for p, n, line in code_lines if NEW_IN_311.search(line)]
    assert offenders == []
