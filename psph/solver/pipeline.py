"""The step pipeline, assembled once from the scene.

A physics stage declares the particle fields it reads and writes and whether it works
on this step's neighbours (the cell lists or the pairs of the sweep). Communication is
derived here, in one place, from those declarations:

- before the first stage that needs neighbours after the positions moved, the search:
  migration and halo exchange, wall ghosts, boundary particles and cell lists;
- before a stage that reads, on neighbours, a field that an earlier stage wrote on owned
  rows since the last search or refresh, a refresh of those fields: the halo copies and
  the wall ghosts and boundary particles that mirror them, for the same neighbours.

No physics stage exchanges, mirrors or searches by itself.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from psph.state.particles import NEIGHBOUR_FIELDS


@dataclass
class Stage:
    """One named stage of a step.

    Parameters
    ----------
    name : str
        The stage's name in summary.json (`stages_run`, `stage_seconds`).
    run : callable
        Does the stage's work on this rank's particle store.
    reads, writes : frozenset of str
        Particle fields (names of `psph.state.particles.FIELDS`) read on neighbours' rows
        and written on owned rows.
    neighbours : bool
        Needs this step's neighbour search (cell lists or recorded pairs) with the halo
        and wall ghosts of the current positions.
    every : int
        Runs on steps that are multiples of this.
    when : callable or None
        A further condition, the same on every rank (e.g. the scheme in force).
    after : tuple of Stage
        For a derived refresh: the writers it follows; it runs when one of them ran in
        the same pass.
    """

    name: str
    run: Callable[[], None]
    reads: frozenset = frozenset()
    writes: frozenset = frozenset()
    neighbours: bool = False
    every: int = 1
    when: Callable[[], bool] | None = None
    after: tuple = ()
    seconds: float = 0.0  # wall time on this rank, accumulated
    calls: int = 0
    last_pass: int = field(default=-1, repr=False)

    def due(self, step: int, pass_no: int) -> bool:
        """Whether the stage runs in pass `pass_no` of the pipeline, at step `step`."""
        if step % self.every:
            return False
        if self.after and not any(w.last_pass == pass_no for w in self.after):
            return False
        return self.when is None or self.when()


def assemble(physics: Sequence[Stage], search: Sequence[Stage],
             refresh: Callable[[tuple[str, ...]], None]) -> list[Stage]:
    """The pipeline of a step: `physics` in order, with the `search` stages and the field
    refreshes (`refresh(fields)`) each stage's declarations call for.

    Parameters
    ----------
    physics : sequence of Stage
        The physics stages, in the order of the step.
    search : sequence of Stage
        The stages that rebuild halo, wall ghosts, boundary particles and neighbour lists
        after particles moved (the step starts after the last step's update moved them).
    refresh : callable
        `refresh(fields)` copies the owners' current values of `fields` into the halo and
        mirrors them on wall ghosts and boundary particles, neighbours unchanged.
    """
    stages: list[Stage] = []
    moved = True
    stale: dict[str, Stage] = {}  # neighbour field -> the stage that last wrote it
    for stage in physics:
        if stage.neighbours and moved:
            stages.extend(search)
            moved = False
            stale.clear()
        elif stage.neighbours:
            need = tuple(f for f in NEIGHBOUR_FIELDS if f in stage.reads and f in stale)
            if need:
                writers = tuple({id(stale[f]): stale[f] for f in need}.values())
                stages.append(_refresh_stage(need, writers, refresh))
                for f in need:
                    del stale[f]
        stages.append(stage)
        for f in stage.writes:
            if f == "x":
                moved = True
            elif f in NEIGHBOUR_FIELDS:
                stale[f] = stage
    return stages


def _refresh_stage(fields: tuple[str, ...], writers: tuple[Stage, ...],
                   refresh: Callable[[tuple[str, ...]], None]) -> Stage:
    every = min(w.every for w in writers)
    name = f"refresh[{','.join(fields)}]" + (f"[every {every}]" if every > 1 else "")
    return Stage(name, lambda: refresh(fields), every=every, after=writers)
