"""psph: MPI-parallel SPH for coupled flow-deformation of saturated soils.

It implements the single-layer (u - p_l) SPH framework, with its three-point integration
(TPI) of the pore pressure and its stabilisation, of

    Lian, Y., Bui, H. H., Nguyen, G. D. and Haque, A. (2023). An effective and stabilised
    (u - p_l) SPH framework for large deformation and failure analysis of saturated
    porous media. Computer Methods in Applied Mechanics and Engineering, 115967.
    doi:10.1016/j.cma.2023.115967

"Eq. (n)", "Section n" and "Fig. n" in the package's docstrings and comments are that
paper's unless another source is named.
"""

import hashlib
import os
import sys
from pathlib import Path

__version__ = "0.1.0"


def kernel_source_key(root: Path) -> str:
    """A hash of every source file under `root` that uses numba (path and content)."""
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if b"numba" in text:
            h.update(str(path.relative_to(root)).encode() + b"\0" + text + b"\0")
    return h.hexdigest()[:16]


def _key_numba_cache() -> None:
    """Point numba's on-disk cache (`cache=True`) at a directory keyed by the kernels'
    sources. numba re-validates a cached function against its own file only, not
    against the njit functions it calls from other files, so an edited
    `plasticity.dp_return` would leave `update.advance` running the old one from the
    cache. With one directory per source hash any change to a numba file compiles every
    kernel once. Parent: $NUMBA_CACHE_DIR if the user set one, else
    $XDG_CACHE_HOME/psph/numba (~/.cache/psph/numba)."""
    base = os.environ.get("PSPH_NUMBA_CACHE_PARENT") or os.environ.get("NUMBA_CACHE_DIR")
    if not base:
        xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        base = str(Path(xdg) / "psph" / "numba")
    os.environ["PSPH_NUMBA_CACHE_PARENT"] = base  # child processes key from the same one
    key_dir = str(Path(base) / kernel_source_key(Path(__file__).parent))
    os.environ["NUMBA_CACHE_DIR"] = key_dir
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = key_dir


_key_numba_cache()
