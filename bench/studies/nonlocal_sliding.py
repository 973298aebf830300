"""The wall band of the non-local softening in a run: a saturated block of the
Section 4.5 clay, with its softening (c 55 -> 0.7 kPa, phi 10 -> 5 deg, eta = 5; psi = 0),
slides at 10 m/s on a fixed base (`sliding.py`), at two spacings with the same
internal length l_c, the block the same size at both (9.6 m x 4.8 m). The base softens
only if the bottom row's eps_hat grows: this is the slope's basal band in a run of
seconds instead of an hour.

Per case, every 0.04 s to 0.4 s (1,000 steps of 4e-4 s): the block's mean velocity, the
basal traction from its momentum balance over the last 0.04 s, the bottom row's mean
Drucker-Prager strength, eps_p and eps_hat (the softening variable the return mapping
used).

    python bench/studies/nonlocal_sliding.py            # the table (about 15 s, one core)
    python bench/studies/nonlocal_sliding.py --quick    # the non-local m = 2 case at
                                                        # dx = 0.6 m, 100 steps

Cases: the local law, and the non-local one with m = 2 (the default, over-non-local)
and m = 1 (the plain average). Writes <out>/nonlocal_sliding.json and .png (basal
traction and the bottom row's eps_hat against time).
"""

import argparse
import json
import sys
from pathlib import Path

from sliding import SLOPE_SOFTENING, sliding_block

OUT = Path(__file__).resolve().parents[1] / "out"

HEIGHT, LENGTH = 4.8, 9.6


def case(dx: float, length: float, m: float, steps: int = 1000, every: int = 100) -> dict:
    """One block: `length` = l_c (0: local law) at spacing dx (`sliding_block`'s rows)."""
    over = list(SLOPE_SOFTENING)
    if length > 0.0:
        over.append("material.plasticity.regularisation="
                    f"{{kind='nonlocal', length={length}, m={m}}}")
    res = sliding_block(over, 10.0, steps, every, round(LENGTH / dx), round(HEIGHT / dx), dx)
    return {"dx": dx, "l_c": length, "m": m, "l_c_over_dx": length / dx,
            "rows": res["rows"]}


def plot(cases: list[dict], path: Path) -> None:
    """Basal traction and the bottom row's eps_hat against time, one line per case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for c in cases:
        rows = [r for r in c["rows"] if "failed" not in r]
        t = [r["time"] for r in rows]
        law = "local" if c["l_c"] == 0.0 else f"m = {c['m']:g}, l_c/dx = {c['l_c_over_dx']:.0f}"
        style = "-" if c["dx"] == 0.4 else "--"
        color = "k" if c["l_c"] == 0.0 else "C3" if c["m"] == 2.0 else "C0"
        ax[0].plot(t, [r["traction_Pa"] / 1e3 for r in rows], style, color=color,
                   label=f"dx = {c['dx']} m, {law}")
        ax[1].plot(t, [r["base_eps_hat"] for r in rows], style, color=color)
    ax[0].set(xlabel="t (s)", ylabel="basal traction (kPa)",
              title="block on a fixed base: traction from its momentum")
    ax[1].set(xlabel="t (s)", ylabel="eps_hat of the bottom row",
              title="the softening variable of the basal row")
    ax[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--length", type=float, default=1.2, help="l_c (m)")
    ap.add_argument("--quick", action="store_true",
                    help="the non-local m = 2 case at dx = 0.6 m, 100 steps (a smoke check)")
    ap.add_argument("--out", type=Path, default=OUT,
                    help="directory of nonlocal_sliding.json and .png (default bench/out)")
    args = ap.parse_args(argv)
    spacings = (0.6,) if args.quick else (0.6, 0.4)
    laws = ((args.length, 2.0),) if args.quick else ((0.0, 1.0), (args.length, 2.0),
                                                      (args.length, 1.0))
    steps, every = (100, 20) if args.quick else (1000, 100)
    out = []
    print(f"{'law':>10} {'dx':>5} {'l_c/dx':>6} {'t':>5} {'v':>6} {'traction':>9} "
          f"{'strength':>9} {'base eps_p':>10} {'base eps_hat':>12}")
    for dx in spacings:
        for length, m in laws:
            c = case(dx, length, m, steps, every)
            out.append(c)
            law = "local" if length == 0.0 else f"m = {m:g}"
            for r in c["rows"]:
                if "failed" in r:
                    print(f"{law:>10} {dx:5.2f} failed at {r['time']:.3f} s: {r['failed']}")
                    continue
                print(f"{law:>10} {dx:5.2f} {c['l_c_over_dx']:6.2f} {r['time']:5.2f} "
                      f"{r['v_mean']:6.2f} {r['traction_Pa'] / 1e3:7.1f}kPa "
                      f"{r['strength_Pa'] / 1e3:7.1f}kPa "
                      f"{r['base_eps_p']:10.3f} {r['base_eps_hat']:12.3f}")
    args.out.mkdir(parents=True, exist_ok=True)
    tag = "" if args.length == 1.2 else f"-lc{args.length:g}"
    (args.out / f"nonlocal_sliding{tag}.json").write_text(json.dumps(out, indent=1))
    plot(out, args.out / f"nonlocal_sliding{tag}.png")
    print(f"wrote {args.out}/nonlocal_sliding{tag}.json and .png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
