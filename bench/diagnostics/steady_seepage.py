"""Steady seepage in the Section 4.5 slope (a variant of docs/findings.md, "The Section 4.5
slope fails without its toe cut"): the head h solves Laplace's equation with h = z on the
ground surface (the plateau and the face, a seepage face: the water table at the surface)
and no flow through the base and the left wall; p = rho_l g (h - z). psph's
`water_table = "surface"` takes Dupuit's hydrostatic p below the local surface instead.
Finite differences on a d x d grid, solved by conjugate gradients (numpy only).

    .venv/bin/python bench/diagnostics/steady_seepage.py   # table, writes /tmp/seep_grid.npz

Then, in a worktree with `steady_seepage_initial.patch` applied (the initial p read from
that grid where PSPH_SEEP_NPZ names it), from the worktree's directory:

    PSPH_SEEP_NPZ=/tmp/seep_grid.npz PYTHONPATH=/tmp/sx NUMBA_CACHE_DIR=/tmp/nc_sx \\
        /work/main/.venv/bin/python -m psph run retrogressive_k0_0.5 --out /tmp/sp_el \\
        --set "remove=[]" --set particles.dx=1.0 --set time.dt=1.0e-3 --set time.end=1.0e-3 \\
        --set "output.times=[]" --set material.plasticity.c=1e9 --set material.plasticity.c_r=1e9
    /work/main/.venv/bin/python -m psph.verify.slope_statics /tmp/sp_el
"""

import math

import numpy as np

D = 0.25
H, L, X_CREST, SLOPE_DEG = 20.0, 180.0, 140.749, 27.0
RHO_G = 1000.0 * 9.81


def ground(x):
    return np.where(x <= X_CREST, H,
                    np.maximum(H - (x - X_CREST) * math.tan(math.radians(SLOPE_DEG)), 0.0))


def main() -> None:
    xs = np.arange(0.5 * D, L, D)
    zs = np.arange(0.5 * D, H, D)
    X, Z = np.meshgrid(xs, zs, indexing="ij")
    inside = Z < ground(X)
    # the operator: per cell, 1 per inner neighbour, 2 per surface face (the surface half a
    # cell away, its head its elevation); no-flow sides add nothing
    diag = np.zeros(X.shape)
    rhs = np.zeros(X.shape)
    shifts = ((1, 0), (-1, 0), (0, 1), (0, -1))
    nbr = []
    for di, dk in shifts:
        other = np.zeros(X.shape, bool)
        nx, nz = X.shape
        src = (slice(max(-di, 0), nx - max(di, 0)), slice(max(-dk, 0), nz - max(dk, 0)))
        dst = (slice(max(di, 0), nx - max(-di, 0)), slice(max(dk, 0), nz - max(-dk, 0)))
        other[src] = inside[dst]  # the neighbour (i + di, k + dk) is soil
        wall = np.zeros(X.shape, bool)  # beyond the grid on the no-flow sides
        if di == -1:
            wall[0, :] = True
        if dk == -1:
            wall[:, 0] = True
        surface = inside & ~other & ~wall
        diag += other & inside
        diag += 2.0 * surface
        rhs += 2.0 * surface * (Z + 0.5 * D * dk)
        nbr.append((other & inside, src, dst))

    def apply(h):
        out = diag * h
        for mask, src, dst in nbr:
            shifted = np.zeros_like(h)
            shifted[src] = h[dst]
            out -= mask * shifted
        return np.where(inside, out, 0.0)

    h = np.where(inside, Z, 0.0)
    r = np.where(inside, rhs, 0.0) - apply(h)
    p_dir = r.copy()
    rr = float((r * r).sum())
    for _ in range(20000):
        ap = apply(p_dir)
        a = rr / float((p_dir * ap).sum())
        h += a * p_dir
        r -= a * ap
        rr_new = float((r * r).sum())
        if math.sqrt(rr_new) < 1e-10 * H * math.sqrt(inside.sum()):
            break
        p_dir = r + rr_new / rr * p_dir
        rr = rr_new
    p = np.where(inside, RHO_G * (h - Z), np.nan)
    print("| x (m) | water thrust, steady seepage (MN/m) | Dupuit (MN/m) "
          "| p at the base, steady / Dupuit (kPa) |")
    print("|---|---|---|---|")
    for xc in (100.0, 141.0, 150.0, 160.0, 170.0):
        i = int(np.argmin(np.abs(xs - xc)))
        steady = float(np.nansum(p[i])) * D
        dupuit = RHO_G * float(ground(xs[i])) ** 2 / 2
        print(f"| {xs[i]:.1f} | {steady / 1e6:.3f} | {dupuit / 1e6:.3f} | "
              f"{p[i, 0] / 1e3:.1f} / {RHO_G * float(ground(xs[i])) / 1e3:.1f} |")
    np.savez("/tmp/seep_grid.npz", xs=xs, zs=zs, p=p, d=D)


if __name__ == "__main__":
    main()
