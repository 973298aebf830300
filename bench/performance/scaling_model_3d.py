"""The scaling model of `scaling_model.py` in 3D: slabs against two-axis cuts.

Measured on this machine (`mpirun` workers of this script) on 1, 2 and 4 ranks of the
throughput bench's 3D coupled elastic TPI block (`throughput.BLOCK_3D`, dx = 0.01 m,
h = 1.3 dx, slabs along its long side z, so a slab face is the block's w x w section):
a particle-step on one rank (c), the node share (s) and halo-row cost (c_h) of a 2-rank
step, messages and bytes per face counted on the communicator, the network by ping-pong
(`scaling_model.fit`, the same constants as in 2D, measured on the 3D step).

The model of one step on P ranks, N particles, a halo of H_P particles per rank sent to
and received from its n_P neighbours:

    T(P) = c (1 + s) N / P + c_h H_P + n_P (m alpha + b (H_P / n_P) / beta)
           + k ceil(log2 P) alpha_c

- slabs along x (one face at P = 2, two beyond; n_P = 2): H_P = 2 r W H / dx^2, r = 3
  halo rows (2h = 2.6 dx); a slab no thinner than its halo, P <= L / (r dx);
- two-axis cuts, P = P_x P_y, the factors with the smallest halo (n_P = 8: four faces
  and four edges): H_P = r H / dx (2 W / (P_y dx) + 2 L / (P_x dx)) + 4 r^2 H / dx, an
  inner rank's (one face per axis cut in two).

The field domain modelled: a hillslope block L x W x H = 8 : 4 : 1 (e.g. 160 x 80 x 20 m,
`slope_3d`'s shape), N = 10^7 and 10^8 particles, on the cluster network of
`scaling_model.CLUSTER` (stated assumptions). The measured 4-rank rows are slabs (the
workers force `decomposition.cuts = "slabs"`); psph's boxes along two axes
(`decomposition/boxes.py`) are measured against slabs on 4 ranks by `halo_layouts.py`;
at cluster scale the two-axis rows are the model's prediction.

    python bench/performance/scaling_model_3d.py              # measures (~40 s), models
    python bench/performance/scaling_model_3d.py --model-only  # from the JSON

Prints the tables, writes <out>/scaling_model_3d.json and .png (`--out`, default bench/out;
`--quick`: blocks of 2,000 and 6,750 particles, a smoke check).
"""

import json
import math
from pathlib import Path

from scaling_model import CLUSTER, bench_main, fit, measure_step, measure_workers
from throughput import BLOCK_3D

OUT = Path(__file__).resolve().parents[1] / "out"
# block side w and height (m) at dx = 0.01: N = w^2 hgt 1e6; steps per timed window
SIZES = {16_000: (0.2, 0.4, 10), 54_000: (0.3, 0.6, 4), 128_000: (0.4, 0.8, 2)}
QUICK_SIZES = {2_000: (0.1, 0.2, 2), 6_750: (0.15, 0.3, 2)}
ROWS = 3  # ceil(2h / dx) at h = 1.3 dx
DOMAIN = (8.0, 4.0, 1.0)  # L : W : H of the modelled hillslope block
P_TABLE = (1, 2, 4, 16, 64, 256, 1024)


def worker(n: int) -> None:
    w, hgt, steps = (SIZES | QUICK_SIZES)[n]
    measure_step(BLOCK_3D.format(n=n, w=w, hgt=hgt, hf=1.3), steps, warm=2)


def measure(quick: bool = False) -> dict:
    return measure_workers(__file__, QUICK_SIZES if quick else SIZES)


def step_time(k: dict, net: dict, n: float, p: int, halo: float, neighbours: int,
              cores: int = 10**9) -> float:
    """Modelled seconds per step: N particles on P ranks, `halo` particles per rank
    exchanged with `neighbours` ranks."""
    if p == 1:
        return k["c_s"] * n
    compute = (k["c_s"] * (1.0 + k["node_share"]) * n / p + k["c_halo_s"] * halo) \
        * max(1.0, p / cores)
    traffic = neighbours * k["messages_per_face"] * net["alpha_s"] \
        + k["bytes_per_halo_particle"] * halo / net["beta_Bps"]
    return compute + traffic + k["collectives"] * math.ceil(math.log2(p)) * net["alpha_coll_s"]


def _cut_halo(px: int, py: int, length: float, w: float, h: float,
              dx: float) -> tuple[float, int]:
    """(halo particles, neighbour ranks) of an inner rank of a P_x x P_y cut."""
    if px * py == 1:
        return 0.0, 0
    faces_x = 0 if px == 1 else 1 if px == 2 else 2
    faces_y = 0 if py == 1 else 1 if py == 2 else 2
    halo = ROWS * h / dx * (faces_x * w / py + faces_y * length / px) / dx \
        + faces_x * faces_y * ROWS**2 * h / dx
    return halo, faces_x + faces_y + faces_x * faces_y


def grid_halo(p: int, length: float, w: float, h: float,
              dx: float) -> tuple[float, int, tuple[int, int]]:
    """The P_x x P_y = P cut with the smallest halo: (its halo, neighbours, (P_x, P_y))."""
    cuts = [(p // py, py) for py in range(1, p + 1) if p % py == 0]
    best = min(cuts, key=lambda c: _cut_halo(*c, length, w, h, dx)[0])
    return (*_cut_halo(*best, length, w, h, dx), best)


def fit_3d(data: dict) -> dict:
    """`scaling_model.fit`, but with the node share s held at 0 where the two-parameter
    fit makes it negative (a 2-rank particle-step faster than a 1-rank one: the halved
    working set, not a shared node): the halo rows' cost c_h alone then takes what the
    owned particles and the messages leave of a 2-rank step."""
    k = fit(data)
    if k["node_share"] >= 0.0:
        return k
    runs = {(r["particles"], r["ranks"]): r for r in data["runs"]}
    net = k["network"]
    num = den = 0.0
    for n in sorted({r["particles"] for r in data["runs"]}):
        r = runs[n, 2]
        comm_s = k["messages_per_face"] * net["alpha_s"] \
            + max(r["bytes_per_step"]) / net["beta_Bps"] + k["collectives"] * net["alpha_coll_s"]
        extra = r["seconds_per_step"] - k["c_s"] * max(r["owned"]) - comm_s
        num += extra * max(r["halo"])
        den += max(r["halo"]) ** 2
    k.update(node_share=0.0, node_share_fit=k["node_share"], c_halo_fit_s=num / den,
             c_halo_s=num / den)
    return k


def check(data: dict, k: dict) -> list[dict]:
    rows = []
    for r in data["runs"]:
        p, n = r["ranks"], r["particles"]
        faces = 0 if p == 1 else 1 if p == 2 else 2
        halo = faces * ROWS * r["face_particles"]
        model = step_time(k, k["network"], n, p, halo, faces, data["cpus"])
        rows.append({"particles": n, "ranks": p, "measured_ms": 1e3 * r["seconds_per_step"],
                     "model_ms": 1e3 * model, "error": model / r["seconds_per_step"] - 1.0,
                     "halo_measured": max(r["halo"]), "halo_model": halo})
    return rows


def projections(k: dict) -> dict:
    out = {}
    net = CLUSTER
    for n in (1e7, 1e8):
        volume = math.prod(DOMAIN)
        scale = (n / volume) ** (1.0 / 3.0)  # particles per unit of the aspect box
        dx = 1.0 / scale
        length, width, height = DOMAIN
        cap = int(length / (ROWS * dx))
        t1 = step_time(k, net, n, 1, 0.0, 0)
        rows = []
        for p in P_TABLE:
            row = {"ranks": p}
            halo_g, nb_g, split = grid_halo(p, length, width, height, dx)
            for name, (halo, nb) in (("slabs", _cut_halo(p, 1, length, width, height, dx)),
                                     ("two_axis", (halo_g, nb_g))):
                if name == "slabs" and p > cap:
                    continue
                t = step_time(k, net, n, p, halo, nb)
                row[name] = {"ms_per_step": 1e3 * t, "efficiency": t1 / (p * t),
                             "halo_over_owned": halo / (n / p), "neighbours": nb}
            row["split"] = split
            rows.append(row)
        out[f"N = {n:.0e}"] = {"particles": n, "dx_over_H": dx / height,
                               "slab_cap_ranks": cap, "strong": rows}
    return out


def report(data: dict, out: Path = OUT) -> None:
    k = fit_3d(data)
    data["fit"], data["check"], data["model"] = k, check(data, k), projections(k)
    net = k["network"]
    print(f"\nconstants (3D step): c = {k['c_s'] * 1e9:.0f} ns per particle-step, halo row "
          f"{k['c_halo_s'] * 1e9:.0f} ns (fitted {k['c_halo_fit_s'] * 1e9:.0f}), "
          f"{100 * k['node_share']:.1f} % slower on a shared node, "
          f"{k['bytes_per_halo_particle']:.0f} B per halo particle, "
          f"{k['messages_per_face']:.1f} messages per face, {k['collectives']:.2f} "
          f"collectives per step; here alpha = {net['alpha_s'] * 1e6:.2f} us, beta = "
          f"{net['beta_Bps'] / 1e9:.2f} GB/s")
    print(f"\n{'N':>9} {'ranks':>5} {'measured ms':>12} {'model ms':>9} {'error':>7} "
          f"{'halo meas.':>11} {'halo model':>11}")
    for r in data["check"]:
        print(f"{r['particles']:9,d} {r['ranks']:5d} {r['measured_ms']:12.1f} "
              f"{r['model_ms']:9.1f} {100 * r['error']:6.1f}% {r['halo_measured']:11,d} "
              f"{r['halo_model']:11,.0f}")
    for name, m in data["model"].items():
        print(f"\n{name}, L x W x H = {DOMAIN}, dx = {m['dx_over_H']:.4f} H, cluster "
              f"network; slab cap {m['slab_cap_ranks']:,} ranks")
        print(f"{'ranks':>6} {'slabs ms':>10} {'eff.':>6} {'halo/own':>9} "
              f"{'P_x x P_y':>10} {'2-axis ms':>10} {'eff.':>6} {'halo/own':>9}")
        for r in m["strong"]:
            s, g = r.get("slabs"), r["two_axis"]
            slab = (f"{s['ms_per_step']:10.1f} {100 * s['efficiency']:5.1f}% "
                    f"{s['halo_over_owned']:9.3f}") if s else f"{'(cap)':>10} {'':6} {'':9}"
            print(f"{r['ranks']:6d} {slab} {r['split'][0]:>4d} x {r['split'][1]:<3d} "
                  f"{g['ms_per_step']:10.1f} {100 * g['efficiency']:5.1f}% "
                  f"{g['halo_over_owned']:9.3f}")
    (out / "scaling_model_3d.json").write_text(json.dumps(data, indent=2) + "\n")
    plot(data, out)
    print(f"wrote {out / 'scaling_model_3d.json'} and {out / 'scaling_model_3d.png'}")


def plot(data: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for name, m in data["model"].items():
        rows = m["strong"]
        for key, style in (("slabs", "s--"), ("two_axis", "o-")):
            sel = [r for r in rows if key in r]
            label = f"{name}, {key.replace('_', '-')}"
            ax1.semilogx([r["ranks"] for r in sel], [100 * r[key]["efficiency"] for r in sel],
                         style, label=label, base=2)
            many = [r for r in sel if r["ranks"] > 1]  # one rank has no halo
            ax2.loglog([r["ranks"] for r in many], [r[key]["halo_over_owned"] for r in many],
                       style, label=label, base=2)
    ax1.set(xlabel="ranks", ylabel="parallel efficiency (%)", ylim=(0, 105),
            title="strong scaling (model, cluster network)")
    ax2.set(xlabel="ranks", ylabel="halo / owned particles", title="halo per rank")
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"psph 3D, hillslope block L:W:H = {DOMAIN}, {data['date']}, "
                 f"{data['machine']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "scaling_model_3d.png", dpi=120)
    plt.close(fig)


def main() -> None:
    bench_main(__doc__, "scaling_model_3d", worker, measure, report)


if __name__ == "__main__":
    main()
