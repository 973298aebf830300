"""What a run reports: the diagnostics row of history.csv, and summary.json (timings
per stage, throughput, memory, load balance, the pressure solve, the verification errors
or metrics)."""

import json
import math
from pathlib import Path

import numpy as np

from psph.config.rules import is_slope_3d
from psph.kernels.update import SCHEME_NONE, SCHEME_PROJECTION
from psph.solver.simulation import Simulation
from psph.verify import history_errors
from psph.verify.collapse import collapse_verification
from psph.verify.collapse_3d import axisymmetric_verification
from psph.verify.slope_3d import slope_verification


def finish(sim, slabs, out, history, setup_seconds, loop_seconds, monitor, probes, status,
            restart=None) -> dict:
    """Summary (and verification errors) on every rank; rank 0 writes history.csv and
    summary.json. Collective."""
    summary = _summary(sim, slabs, setup_seconds, loop_seconds, monitor)
    summary["status"] = status
    if restart is not None:
        summary["restarted_from"] = str(restart)
    scene = sim.scene
    rank0 = slabs.rank == 0
    verification = None
    if rank0 and history:
        cols = {k: np.array([r.get(k, np.nan) for r in history]) for k in history[0]}
        verification = history_errors(scene, cols, {k: pos for k, (_, pos) in probes.items()})
    if scene.verification.reference == "collapse" and status == "finished":
        axisymmetric = scene.dim == 3 and len(scene.particles.cylinders) == 1
        verify = axisymmetric_verification if axisymmetric else \
            slope_verification if is_slope_3d(scene) else collapse_verification
        verification = verify(out / "particles.h5", scene, slabs.comm)
        if history:
            verification["p_max_Pa"] = max(r["p_max"] for r in history)
            verification["p_min_Pa"] = min(r["p_min"] for r in history)
    verification = slabs.comm.bcast(verification, root=0)
    if verification is not None:
        summary["errors" if "collapse" not in verification else "metrics"] = verification
    if rank0:
        write_history(out / "history.csv", history)
        (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return summary


def history_row(sim: Simulation, probes: dict[str, tuple[int, tuple]]) -> dict:
    """One diagnostics row (collective): surface settlement, kinetic energy, max p, and p
    and displacement of each probe particle (its owner contributes, the others add 0)."""
    st = sim.store
    n = st.n_owned
    surf = st.surface[:n] > 0
    dim = sim.dim
    w = 1 + dim  # p and u of a probe
    local = np.zeros(3 + w * len(probes))
    local[0] = -st.u[:n, dim - 1][surf].sum()
    local[1] = float(surf.sum())
    local[2] = 0.5 * np.sum(st.rho[:n] * st.vol[:n] * np.sum(st.v[:n] ** 2, axis=1))
    keys = st.key[:n]
    for k, (pid, _) in enumerate(probes.values()):
        hit = np.flatnonzero(keys == pid)
        if len(hit):
            i = hit[0]
            local[3 + w * k] = st.p[i]
            local[4 + w * k:3 + w * (k + 1)] = st.u[i]
    tot = sim.slabs.allreduce_sum(local)
    pmax = sim.slabs.allreduce_max(float(np.max(st.p[:n])) if n else -math.inf)
    pmin = -sim.slabs.allreduce_max(float(-np.min(st.p[:n])) if n else -math.inf)
    row = {"time": sim.t, "step": sim.step,
           "settlement": tot[0] / tot[1] if tot[1] > 0 else 0.0,
           "kinetic_energy": tot[2], "p_max": pmax, "p_min": pmin,
           "imbalance": sim.slabs.imbalance(st)}
    if sim.stepping.scheme_main == SCHEME_PROJECTION:
        row["cg_iterations"] = sim.solve["iterations"]
        row["cg_residual"] = sim.solve["residual"]
    elif sim.stepping.scheme_main != SCHEME_NONE:
        # the same measure at the explicit / TPI pressure (0 before the first step)
        row["mass_balance_residual"] = sim.mass_balance_residual() if sim.step > 0 else 0.0
    for k, name in enumerate(probes):
        row[f"p_{name}"] = tot[3 + w * k]
        for d in range(dim):
            row[f"u{'xyz'[d]}_{name}"] = tot[4 + w * k + d]
    return row


def write_history(path: Path, rows: list[dict]) -> None:
    if not rows:
        return
    keys = list(rows[0])
    lines = [",".join(keys)] + [",".join(f"{r[k]:.10g}" for k in keys) for r in rows]
    path.write_text("\n".join(lines) + "\n")


def peak_rss_bytes() -> int:
    """Peak resident memory of this process so far (bytes; Linux reports KiB)."""
    import resource

    return int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss) * 1024


def _summary(sim, slabs, setup_seconds, loop_seconds, monitor) -> dict:
    comm = slabs.comm
    stage_local = {s.name: s.seconds for s in sim.stages}
    gathered = comm.allgather(stage_local)
    stages = {name: {"max_s": max(g[name] for g in gathered),
                     "mean_s": sum(g[name] for g in gathered) / len(gathered),
                     "calls": next(s.calls for s in sim.stages if s.name == name)}
              for name in stage_local}
    steps = sim.step - sim.first_step  # this run's share (a restart starts later)
    psteps = sim.n_global * steps
    memory = comm.allgather((peak_rss_bytes(), sim.state_bytes(), sim.store.n_owned))
    layout = slabs.describe()
    summary = {
        "scene": sim.scene.name,
        "wall_time_s": setup_seconds + loop_seconds,
        "setup_s": setup_seconds,
        "loop_s": loop_seconds,
        "steps": sim.step,
        "end_time_s": sim.t,
        "particles": sim.n_global,
        "ranks": slabs.size,
        "dt": {"main_s": sim.stepping.dt_main, "explicit_s": sim.stepping.dt_explicit,
               **sim.stepping.limits},
        "steps_this_run": steps,
        "steps_per_second": steps / loop_seconds if loop_seconds > 0 else None,
        "particle_steps_per_second": psteps / loop_seconds if loop_seconds > 0 else None,
        "particle_steps_per_second_per_core":
            psteps / loop_seconds / slabs.size if loop_seconds > 0 else None,
        "stages_run": [s.name for s in sim.stages],
        "memory": {
            "peak_rss_bytes_per_rank": [m[0] for m in memory],
            "state_bytes_per_rank": [m[1] for m in memory],
            "state_bytes_per_owned_particle": max(m[1] / max(m[2], 1) for m in memory),
        },
        "load_balance": {
            "measure": "max/mean particles owned per rank",
            "threshold": sim.scene.decomposition.imbalance_threshold,
            "check_every_steps": sim.scene.decomposition.rebalance_every,
            "rebalances": slabs.rebalances,
            "imbalance_final": slabs.imbalance(sim.store),
            "imbalance_max_seen": slabs.max_imbalance,
            "imbalance_max_after_recut": slabs.max_after_recut,
            "cuts": layout.get("cuts", layout.get("cuts0")),
        },
        "decomposition": {**layout, "halo_rows_per_rank": comm.allgather(sim.store.n_halo),
                          "owned_per_rank": comm.allgather(sim.store.n_owned)},
        "stage_seconds": stages,
    }
    if sim.stepping.scheme_main == SCHEME_PROJECTION:
        sv = sim.solve
        summary["pressure_solve"] = {
            "method": "matrix-free conjugate gradients, Jacobi, exact (rank-independent) "
                      "inner products",
            "tolerance": sim.scene.pressure.tolerance,
            "iterations_mean": sv["iterations_total"] / max(steps, 1),
            "iterations_max": sv["iterations_max"],
            "steps_not_converged": sv["not_converged"],
            "dt_limit_in_force": "dt_solid_eq41" if sim.scene.time.dt is None else "time.dt"}
    if sim.equilibrium:
        summary["equilibrate"] = sim.equilibrium
    if monitor is not None:
        summary["errors"] = monitor.errors()
    return summary
