"""Citations name what a reader of the repository can open.

A source is cited as a public document (paper, book chapter, repository@commit) or as a document the
repository ships: the project's reading of the techniques' sources is ``docs/SOURCES.md``, cited as
"SOURCES §N.M"; the integral is ``docs/PHYSICS.md``; measured figures are in ``BENCHMARKS.md``. No
file cites notes kept outside the repository (research notes, seed texts, design notes, a ``shared/``
folder) or an issue number, which means nothing to a reader of the repository. The one ``shared/``
path allowed is the test data read in place (tests/test_medium.py), never copied into the repository.
"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCANNED_DIRS = ("vlref", "tests", "benchmarks", "ports", "docs", "notebooks")
SCANNED_FILES = ("README.md", "BENCHMARKS.md", "setup.cfg")
TEXT_SUFFIXES = {".py", ".md", ".toml", ".wgsl", ".sh", ".cfg", ".txt", ".ipynb"}
ALLOWED_SHARED = "/work/shared/data/"

FORBIDDEN = {
    "a section of the unshipped research notes (cite SOURCES §N.M)":
        re.compile(r"\bresearch\s+(?:§|section\s+\d|appendix|app\.)", re.IGNORECASE),
    "the unshipped research notes (cite docs/SOURCES.md)": re.compile(r"seed-algorithms|ecosystem-and-peers"),
    "the unshipped design notes (cite docs/PHYSICS.md)": re.compile(r"\bDESIGN\.md\b"),
    "a seed text (cite the public source)": re.compile(r"\bseeds?\s+0\d\d\b", re.IGNORECASE),
    "an issue number (say what was asked, or point to BENCHMARKS.md)":
        re.compile(r"\bissues?[ -]?#?\d+", re.IGNORECASE),
}
SHARED_PATH = re.compile(r"(?<![\w.-])(?:/work/)?shared/\S*")

SECTION = r"(?:§\s*\d+(?:\.\d+)?|Appendix [A-Z])"
SOURCES_CITATION = re.compile(rf"SOURCES(?:\.md)?`{{0,2}}\s*({SECTION}(?:\s*(?:/|,|and)\s*{SECTION})*)")
HEADING_POINTER = re.compile(r"\b((?:docs/)?[A-Z]+\.md)`{0,2} \"([^\"]+)\"")


def _scanned():
    files = [ROOT / name for name in SCANNED_FILES]
    for d in SCANNED_DIRS:
        files += sorted(p for p in (ROOT / d).rglob("*") if p.is_file() and p.suffix in TEXT_SUFFIXES)
    me = Path(__file__).resolve()
    return [p for p in files if p.exists() and p.resolve() != me]


def _lines(path):
    return path.read_text(encoding="utf-8").splitlines()


def _headings(path):
    return [line.lstrip("#").strip() for line in _lines(path) if line.startswith("#")]


def _sources_sections():
    """Section labels of docs/SOURCES.md's headings: "1", "1.9", "Appendix A", ..."""
    labels = set()
    for h in _headings(ROOT / "docs" / "SOURCES.md"):
        m = re.match(r"(\d+(?:\.\d+)?)[.\s]", h + " ")
        if m:
            labels.add(m.group(1))
        m = re.match(r"Appendix ([A-Z])\b", h)
        if m:
            labels.add(f"Appendix {m.group(1)}")
    return labels


def test_the_scan_covers_the_code_tests_and_docs():
    names = {p.relative_to(ROOT).as_posix() for p in _scanned()}
    assert {"vlref/march/physical.py", "docs/TECHNIQUES.md", "docs/SOURCES.md", "BENCHMARKS.md",
            "ports/wgpu/README.md", "benchmarks/froxel_temporal.py", "tests/test_medium.py"} <= names


def test_no_file_cites_a_document_outside_the_repository():
    found = []
    for path in _scanned():
        for no, line in enumerate(_lines(path), 1):
            where = f"{path.relative_to(ROOT)}:{no}"
            found += [f"{where}: {what}: {m.group(0)!r}" for what, rx in FORBIDDEN.items() for m in rx.finditer(line)]
            found += [f"{where}: a shared/ path: {m.group(0)!r}" for m in SHARED_PATH.finditer(line)
                      if not m.group(0).startswith(ALLOWED_SHARED)]
    assert not found, "\n".join(found)


def test_the_patterns_catch_the_old_citations():
    old = ["(research §1.9)", "research section 4", "``research/seed-algorithms.md`` §1", "of DESIGN.md",
           "the thesis (seed 000)", "(issue 12: a light", "Issue 8's targets", "pre-issue-12", "issue #15"]
    for text in old:
        assert any(rx.search(text) for rx in FORBIDDEN.values()), text
    assert SHARED_PATH.search("`shared/research/notes.md`")
    assert SHARED_PATH.search("/work/shared/data/x.bytes").group(0).startswith(ALLOWED_SHARED)
    assert not any(rx.search("thesis §4.2.6; SOURCES §1.9; hypothesis 6 and its research question")
                   for rx in FORBIDDEN.values())


def test_every_sources_section_cited_is_a_heading_of_docs_sources():
    labels = _sources_sections()
    assert {"0", "1", "1.9", "2.5", "4", "5", "6.5", "6.9", "7", "Appendix A"} <= labels
    cited, missing = 0, []
    for path in _scanned():
        for no, line in enumerate(_lines(path), 1):
            for m in SOURCES_CITATION.finditer(line):
                for label in re.findall(SECTION, m.group(1)):
                    label = label.replace("§", "").strip()
                    cited += 1
                    if label not in labels:
                        missing.append(f"{path.relative_to(ROOT)}:{no}: SOURCES {label}")
    assert cited >= 40
    assert not missing, "\n".join(missing)


def test_every_named_section_of_a_shipped_document_exists():
    """``BENCHMARKS.md "Targets"`` or ``docs/PHYSICS.md "The integral"`` names the start of a heading there."""
    pointers, missing = 0, []
    for path in _scanned():
        for no, line in enumerate(_lines(path), 1):
            for m in HEADING_POINTER.finditer(line):
                name, title = m.groups()
                doc = next((p for p in (ROOT / name, ROOT / "docs" / name) if p.exists()), None)
                pointers += 1
                if doc is None or not any(h.startswith(title) for h in _headings(doc)):
                    missing.append(f"{path.relative_to(ROOT)}:{no}: {name} \"{title}\"")
    assert pointers >= 8
    assert not missing, "\n".join(missing)
