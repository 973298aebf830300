"""numba's cache is keyed by the kernels' sources (psph/__init__.py): numba checks a cached
function against its own file only, so an edited callee in another file (dp_return)
left its caller (advance) running stale code."""

import os
import subprocess
import sys
from pathlib import Path

import psph
from psph import kernel_source_key


def test_key_follows_numba_sources_only(tmp_path):
    (tmp_path / "kernels").mkdir()
    callee = tmp_path / "kernels" / "callee.py"
    callee.write_text("import numba\n\ndef f(x):\n    return x\n")
    other = tmp_path / "run.py"
    other.write_text("print('no kernels here')\n")
    key = kernel_source_key(tmp_path)
    other.write_text("print('still none')\n")
    assert kernel_source_key(tmp_path) == key
    callee.write_text("import numba\n\ndef f(x):\n    return 2 * x\n")
    assert kernel_source_key(tmp_path) != key


def test_numba_cache_dir_is_keyed_and_inherited_without_nesting():
    here = os.environ["NUMBA_CACHE_DIR"]
    assert here.endswith(kernel_source_key(Path(psph.__file__).parent))
    child = subprocess.run([sys.executable, "-c", "import psph, numba; "
                            "print(numba.config.CACHE_DIR)"], capture_output=True, text=True,
                           check=True)
    assert child.stdout.strip() == here
