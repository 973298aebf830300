"""The step's kernels in the scene's dimension: the 2D or the 3D specialisation of each
kernel factory (`psph/kernels/dims.py`), picked once when the pipeline is assembled."""

from typing import NamedTuple

from psph.kernels import images, interactions, laplacian, projection, shepard, update


class KernelSet(NamedTuple):
    """The kernels whose compiled code depends on the dimension (the others read it
    from the arrays' shapes or need none)."""

    pair_sums: object
    velocity_gradient_sums: object
    kick: object
    advance: object
    projection_rhs: object
    pair_weights: object
    image_sums: object
    shepard_pressure: object
    shepard_stress: object
    mls_stress: object
    moment_columns: int  # the Shepard step's scratch: the MLS filter of the stress


KERNELS = {
    2: KernelSet(interactions.pair_sums, interactions.velocity_gradient_sums, update.kick,
                 update.advance, projection.projection_rhs, laplacian.pair_weights,
                 images.image_sums, shepard.shepard_pressure, shepard.shepard_stress,
                 shepard.mls_stress, shepard.moment_width(2, True, 4)),
    3: KernelSet(interactions.pair_sums_3d, interactions.velocity_gradient_sums_3d,
                 update.kick_3d, update.advance_3d, projection.projection_rhs_3d,
                 laplacian.pair_weights_3d, images.image_sums_3d, shepard.shepard_pressure_3d,
                 shepard.shepard_stress_3d, shepard.mls_stress_3d,
                 shepard.moment_width(3, True, 6)),
}


def kernels_for(dim: int) -> KernelSet:
    """The kernels of a `dim`-dimensional run (2 or 3)."""
    return KERNELS[dim]
