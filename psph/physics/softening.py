"""The regularised softening stage: the over-non-local equivalent plastic strain that
drives the softening of Eq. (17)-(19) of Lian et al. (2023) for the materials with
`plasticity.regularisation` (psph/kernels/nonlocal_strain.py); the other materials keep
the local law. The averaging reads eps_p of the halo rows, which `exchange` sends with
the full state: the halo is at least 2 l_c deep (`reach`, taken by `boundary.halo_width`),
so every owned particle's support is on its rank."""

from __future__ import annotations

import numpy as np

from psph.kernels.bundles import CellList, NonlocalFields, fields_of
from psph.kernels.nonlocal_strain import nonlocal_strain, nonlocal_strain_3d, rings_for


def _regularisations(scene) -> list:
    return [m.plasticity.regularisation if m.plasticity is not None else None
            for m in scene.material_list]


def reach(scene) -> float:
    """The support radius 2 l_c of the widest regularisation.

    Parameters
    ----------
    scene : Scene
        the validated scene.

    Returns
    -------
    float
        2 l_c (m); 0 without any regularised material.
    """
    return max((2.0 * r.length for r in _regularisations(scene) if r is not None),
               default=0.0)


class NonlocalSoftening:
    """l_c and m per material, and the step's eps_hat of the owned rows (`eps_hat`, grown
    with the store, never per step)."""

    def __init__(self, scene, cell_size: float, wall_axis: np.ndarray,
                 wall_pos: np.ndarray):
        """The stage of a scene.

        Parameters
        ----------
        scene : Scene
            the validated scene.
        cell_size : float
            side of the step's cells (m).
        wall_axis : int array
            normal axes of the walls whose mirror images enter the averages.
        wall_pos : float array
            their positions (m).
        """
        regs = _regularisations(scene)
        self.wall_axis = np.asarray(wall_axis, np.int64)
        self.wall_pos = np.asarray(wall_pos, float)
        self.lengths = np.array([r.length if r is not None else 0.0 for r in regs])
        self.weights = np.array([r.m if r is not None else 1.0 for r in regs])
        self.rings = rings_for(float(self.lengths.max()), cell_size)
        self.eps_hat = np.zeros(0)
        self.plastic_cell = np.zeros(0, np.int8)  # cells holding plastic strain (scratch)

    def name(self) -> str:
        """The stage's name in the progress output, with its internal lengths (m)."""
        lc = ", ".join(f"{v:g}" for v in self.lengths if v > 0.0)
        return f"nonlocal_eps_p[l_c {lc} m]"

    def average(self, store, cell_of: np.ndarray, cell_start: np.ndarray,
                order: np.ndarray, ncell: np.ndarray) -> None:
        """eps_hat of the owned rows from this step's cell lists (positions unchanged
        since the neighbour search), into `self.eps_hat`.

        Parameters
        ----------
        store : ParticleStore
            the particles (owned, halo with eps_p, boundary rows).
        cell_of, cell_start, order, ncell : int64 arrays
            the step's cell lists (cells of side 2h).
        """
        st = store
        if self.eps_hat.shape[0] < st.cap:
            self.eps_hat = np.zeros(st.cap)
        cells = int(np.prod(ncell))
        if self.plastic_cell.shape[0] < cells:
            self.plastic_cell = np.zeros(2 * cells, np.int8)
        average = nonlocal_strain if len(ncell) == 2 else nonlocal_strain_3d
        average(st.n_owned, st.n_real, fields_of(NonlocalFields, st.arrays), self.lengths,
                self.weights, CellList(cell_of, cell_start, order, ncell), self.rings,
                self.plastic_cell, self.wall_axis, self.wall_pos, self.eps_hat)


def nonlocal_softening(scene, cell_size: float, wall_axis: np.ndarray,
                       wall_pos: np.ndarray) -> NonlocalSoftening | None:
    """The stage's state, or None when no material is regularised (the local law).

    Parameters
    ----------
    scene, cell_size, wall_axis, wall_pos
        as `NonlocalSoftening`.

    Returns
    -------
    NonlocalSoftening or None
    """
    return NonlocalSoftening(scene, cell_size, wall_axis, wall_pos) \
        if reach(scene) > 0.0 else None
