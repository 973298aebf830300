"""The repository's text speaks of the physics and of itself only.

The package (psph/, its scenes included), README.md and the documentation (docs/, except the
history page docs/history.md and generated or binary files) carry no work-item numbers
("issue 13", "task 4", "PR #12") and no paths outside the repository (the workspace, a
home directory, design notes kept elsewhere). The package also names no README section
and no date: a comment says what and why, the history lives in git and docs/history.md.
Every repository path that README.md, the documentation and the package's text write
(`bench/....py`, `psph/....py`, `tests/....py`, `docs/....md`, `jobs/...`) exists, so
that a documented command or a cited study does not rot.

Fast (a text scan, no MPI, no numba); each failure lists `file:line: text`.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path
from typing import NamedTuple

import pytest

ROOT = Path(__file__).resolve().parents[1]

# (pattern, what it is): in every scanned file
WORK_ITEMS = (
    (re.compile(r"\b[Ii]ssues?\s+#?\d+"), "work-item number"),
    (re.compile(r"\b[Tt]asks?\s+#?\d+"), "work-item number"),
    (re.compile(r"\b(?:PR|[Pp]ull request|[Tt]ickets?|[Bb]ugs?|[Ii]tems?|[Ff]ix(?:es|ed)?"
                r"|[Cc]loses?|[Rr]esolves?)\s*#\d+\b"), "work-item number"),
    (re.compile(r"(?<![\w&])\(#\d+\)"), "work-item number"),
    (re.compile(r"\b[Gg][Hh]-\d+\b"), "work-item number"),
)
OUTSIDE_PATHS = (
    (re.compile(r"\.\./shared\b"), "path outside the repository"),
    (re.compile(r"(?<![\w.])/work/"), "path outside the repository"),
    (re.compile(r"\bDESIGN\.md\b"), "document outside the repository"),
    (re.compile(r"\bSTYLE\.md\b"), "document outside the repository"),
    (re.compile(r"(?<![\w.~])/(?:home|Users)/[\w.-]+"), "absolute home path"),
    (re.compile(r"(?<![\w.~])/root/"), "absolute home path"),
)
# in the package only: its comments and docstrings cite equations, not the README or a day
PACKAGE_ONLY = (
    (re.compile(r"\bREADME\b"), "reference to the README"),
    (re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b"), "date"),
)
# a repository path as README.md and the docs write it
REPO_PATH = re.compile(r"(?<![\w./-])((?:bench|psph|tests|docs)/[\w./-]*\w\.(?:py|md)(?![\w/])"
                       r"|jobs/[\w./-]*\w)")
# written at build time, absent from a fresh clone
GENERATED = ("docs/_build/", "docs/reference/")

BINARY_SUFFIXES = {".png", ".jpg", ".jpeg", ".gif", ".svg", ".pdf", ".ico", ".h5", ".npz",
                   ".npy", ".pyc", ".so", ".gz", ".zip"}


class Hit(NamedTuple):
    path: str
    line: int
    text: str
    what: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.text.strip()}  [{self.what}]"


def text_hits(text: str, path: str = "<text>", package: bool = False) -> list[Hit]:
    """Work-item numbers and outside paths in `text` (and, with `package`, README
    references and dates), one `Hit` per line and kind."""
    checks = WORK_ITEMS + OUTSIDE_PATHS + (PACKAGE_ONLY if package else ())
    hits = []
    for n, line in enumerate(text.splitlines(), start=1):
        seen = set()
        for pattern, what in checks:
            if what not in seen and pattern.search(line):
                seen.add(what)
                hits.append(Hit(path, n, line, what))
    return hits


def missing_paths(text: str, path: str = "<text>", root: Path = ROOT) -> list[Hit]:
    """The repository paths written in `text` that do not exist under `root`."""
    hits = []
    for n, line in enumerate(text.splitlines(), start=1):
        for m in REPO_PATH.finditer(line):
            p = m.group(1)
            if p.startswith(GENERATED) or (root / p).exists():
                continue
            hits.append(Hit(path, n, line, f"no such path: {p}"))
    return hits


def _scanned(rel: Path) -> bool:
    parts = rel.parts
    if "__pycache__" in parts or parts[:2] in (("docs", "_build"), ("docs", "reference")):
        return False
    if rel.suffix.lower() in BINARY_SUFFIXES:
        return False
    if parts[:2] == ("docs", "data") and ".json" in rel.name:
        return False
    return rel != Path("docs/history.md")


def repository_files(root: Path = ROOT) -> list[Path]:
    """The scanned files: psph/, README.md and docs/ as git sees them (tracked, or new
    and not ignored), without the history page, generated and binary files."""
    where = ("psph", "README.md", "docs")
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others",
                              "--exclude-standard", "--", *where],
                             cwd=root, capture_output=True, check=True).stdout
        rels = [Path(p) for p in out.decode().split("\0") if p]
    except (OSError, subprocess.CalledProcessError):  # not a git checkout
        rels = [p.relative_to(root) for w in where for p in
                ([root / w] if (root / w).is_file() else (root / w).rglob("*"))]
    return sorted(root / r for r in rels if _scanned(r) and (root / r).is_file())


def _read(path: Path) -> str | None:
    data = path.read_bytes()
    if b"\0" in data:
        return None
    return data.decode("utf-8", errors="replace")


def _report(hits: list[Hit]) -> str:
    return f"{len(hits)} line(s):\n" + "\n".join(str(h) for h in hits)


# --- the checker itself ---------------------------------------------------------------

PLANTED_KERNEL = '''
@nb.njit(cache=True)
def kernel(x, out):
    """out = 2 x (Eq. 38)."""
    # issue 12: x
    for i in range(x.shape[0]):
        out[i] = 2.0 * x[i]
'''


def test_a_planted_work_item_is_flagged():
    hits = text_hits(PLANTED_KERNEL, "psph/kernels/fake.py", package=True)
    assert [(h.line, h.what) for h in hits] == [(5, "work-item number")], _report(hits)
    assert str(hits[0]) == "psph/kernels/fake.py:5: # issue 12: x  [work-item number]"


@pytest.mark.parametrize("line", [
    "# issue 13",
    "issues 17 and 23",
    "the contract (issue 39).",
    "Issue 38. The Section 4.5 slope",
    "see issue #7",
    "task 4: the docs",
    "Tasks 2-3",
    "merged in PR #12",
    "fixes #3",
    "the change (#41)",
    "gh-1207",
    "the paper (" + "../" + "shared/paper/u-pl-sph-tpi-paper.txt)",  # in parts
    "written to " + "/work" + "/main/runs",
    "interfaces: DESIGN.md",
    "as STYLE.md says",
    "in /home/alice/psph",
    "copied to /root/.cache",
    "/Users/bob/runs",
])
def test_the_checker_flags(line):
    assert text_hits(line), line


@pytest.mark.parametrize("line", [
    "Eq. (38) of Lian et al. (2023)",
    "Eqs. (17)-(19)",
    "Fig. 16 and Figs. 18-26",
    "Section 4.5, Table 1",
    'color="#1f77b4"',
    "color: #333333;",
    "# 1D harmonic consolidation",
    "x = a[3]  # 3 columns",
    "the issue is the support",
    "a tissue 3 mm thick",
    "no issues",
    "~/.cache/psph/numba",
    "$XDG_CACHE_HOME/psph/numba",
    "OUT/work/particles.h5",
    "ref. [11] (Bui et al. 2008)",
    "docs/history.md",
])
def test_the_checker_passes(line):
    assert not text_hits(line, package=True), text_hits(line, package=True)


def test_package_only_checks():
    line = "(README, \"Pore pressure through failure\"), measured on 2026-12-05"
    assert not text_hits(line)
    assert {h.what for h in text_hits(line, package=True)} == {"reference to the README",
                                                               "date"}


def test_missing_paths_are_flagged(tmp_path):
    (tmp_path / "bench").mkdir()
    (tmp_path / "bench" / "real.py").write_text("")
    text = ("`python bench/real.py` then `python bench/gone.py --quick`.\n"
            "See docs/guide/nope.md, psph/kernels/nope.py and jobs/nope.sh.\n"
            "Built: docs/reference/scene_keys.md; a pattern: bench/diagnostics/*.py\n")
    hits = missing_paths(text, "README.md", root=tmp_path)
    assert [(h.line, h.what) for h in hits] == [
        (1, "no such path: bench/gone.py"), (2, "no such path: docs/guide/nope.md"),
        (2, "no such path: psph/kernels/nope.py"), (2, "no such path: jobs/nope.sh")]


# --- the tree ---------------------------------------------------------------------------

def test_no_work_items_or_outside_paths_in_the_tree():
    hits = []
    for path in repository_files():
        text = _read(path)
        if text is not None:
            rel = path.relative_to(ROOT).as_posix()
            hits += text_hits(text, rel, package=rel.startswith("psph/"))
    assert not hits, _report(hits)


def test_documented_paths_exist():
    docs = [p for p in repository_files() if p.suffix == ".md"
            and p.relative_to(ROOT).parts[0] in ("README.md", "docs")]
    assert any(p.name == "README.md" for p in docs)
    hits = []
    for path in docs:
        hits += missing_paths(_read(path) or "", path.relative_to(ROOT).as_posix())
    assert not hits, _report(hits)


def test_paths_in_the_package_exist():
    hits = []
    for path in repository_files():
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("psph/"):
            hits += missing_paths(_read(path) or "", rel)
    assert not hits, _report(hits)
