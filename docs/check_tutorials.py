"""Run the tutorials' commands, so that they cannot rot (`make docs-check`).

A fenced ```bash block of a page under docs/tutorials/ whose first line is `# docs-check`
is run, in page order, with bash (`set -euo pipefail`) in a scratch directory per page
(with `.venv` linked to the project's environment and PYTHONPATH at the project), so the
blocks of one page share their files (a scene written by one block is run by the next).
`# docs-check: ARGS` also appends ARGS (e.g. `--set time.end=0.1`) to every
`psph run` command of the block: the page shows the full run, the check a short one.

    python docs/check_tutorials.py [--venv DIR] [--keep] [PAGE.md ...]

Exit 0 when every block exits 0; else 1, naming the page, the block and its output.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
MARK = re.compile(r"^#\s*docs-check(?::\s*(?P<args>.*))?\s*$")
FENCE = re.compile(r"^```(?:\{code-block\}\s*)?(?P<lang>[\w-]*)\s*$")
RUN = re.compile(r"(-m psph run \S+)")

MPI_ENV = {
    "OMPI_ALLOW_RUN_AS_ROOT": "1",
    "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
    "OMPI_MCA_rmaps_base_oversubscribe": "1",
    "OMPI_MCA_btl": "self,vader,tcp",
    "OMPI_MCA_btl_vader_single_copy_mechanism": "none",
    "NUMBA_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
}


def blocks(page: Path) -> list[tuple[int, str, str]]:
    """(line number, extra run arguments, script) of each checked block of a page."""
    out, lines, i = [], page.read_text().splitlines(), 0
    while i < len(lines):
        m = FENCE.match(lines[i].strip())
        if m and m.group("lang") in ("bash", "sh", "shell", "console"):
            start, body = i + 1, []
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                body.append(lines[i])
                i += 1
            mark = MARK.match(body[0].strip()) if body else None
            if mark:
                out.append((start + 1, (mark.group("args") or "").strip(),
                            "\n".join(body[1:]) + "\n"))
        i += 1
    return out


def with_args(script: str, args: str) -> str:
    """Append `args` to every `psph run` command of a script (before a trailing comment
    or continuation; heredoc bodies are left alone)."""
    if not args:
        return script
    out, heredoc = [], None
    for line in script.splitlines():
        if heredoc:
            out.append(line)
            if line.strip() == heredoc:
                heredoc = None
            continue
        h = re.search(r"<<-?\s*'?(\w+)'?", line)
        if h:
            heredoc = h.group(1)
        if RUN.search(line):
            line = RUN.sub(lambda m: f"{m.group(1)} {args}", line, count=1)
        out.append(line)
    return "\n".join(out) + "\n"


def run_page(page: Path, venv: Path, keep: bool) -> tuple[int, list[str]]:
    passed, failures = 0, []
    work = Path(tempfile.mkdtemp(prefix=f"docs-check-{page.stem}-"))
    (work / ".venv").symlink_to(venv)
    env = dict(os.environ, **MPI_ENV)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    try:
        for line, args, script in blocks(page):
            body = "set -euo pipefail\n" + with_args(script, args)
            t0 = time.time()
            proc = subprocess.run(["bash", "-c", body], cwd=work, env=env,
                                  capture_output=True, text=True)
            where = f"{page.relative_to(ROOT)}:{line}"
            print(f"docs-check: {where}: exit {proc.returncode} in {time.time() - t0:.1f} s",
                  flush=True)
            passed += proc.returncode == 0
            if proc.returncode != 0:
                failures.append(f"{where}: exit {proc.returncode}\n--- script\n{body}"
                                f"--- stdout\n{proc.stdout[-4000:]}\n--- stderr\n"
                                f"{proc.stderr[-4000:]}")
                break  # later blocks of the page build on this one
    finally:
        if keep:
            print(f"docs-check: kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)
    return passed, failures


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("pages", nargs="*", type=Path)
    ap.add_argument("--venv", type=Path, default=Path(sys.prefix),
                    help="the environment the commands' .venv/bin/python is (default: the "
                         "one running this script, as `make docs-check` runs it from .venv)")
    ap.add_argument("--keep", action="store_true", help="keep the scratch directories")
    a = ap.parse_args(argv)
    pages = a.pages or sorted((DOCS / "tutorials").glob("*.md"))
    venv = a.venv.resolve()
    if not (venv / "bin" / "python").exists():
        print(f"docs-check: no {venv}/bin/python (run make env)", file=sys.stderr)
        return 1
    t0, failures, passed, n = time.time(), [], 0, 0
    for page in pages:
        page = page.resolve()
        n += len(blocks(page))
        ok, bad = run_page(page, venv, a.keep)
        passed, failures = passed + ok, failures + bad
    for f in failures:
        print(f, file=sys.stderr)
    print(f"docs-check: {passed} of {n} blocks passed, {len(failures)} failed "
          f"({len(pages)} pages, {time.time() - t0:.0f} s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
