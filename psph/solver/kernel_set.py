"""The step's kernels in the scene's dimension: the 2D or the 3D specialisation of each
kernel factory (`psph/kernels/dims.py`), picked once when the pipeline is assembled."""

from typing import NamedTuple

from psph.kernels import images, interactions, laplacian, projection, update


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


KERNELS = {
    2: KernelSet(interactions.pair_sums, interactions.velocity_gradient_sums, update.kick,
                 update.advance, projection.projection_rhs, laplacian.pair_weights,
                 images.image_sums),
    3: KernelSet(interactions.pair_sums_3d, interactions.velocity_gradient_sums_3d,
                 update.kick_3d, update.advance_3d, projection.projection_rhs_3d,
                 laplacian.pair_weights_3d, images.image_sums_3d),
}


def kernels_for(dim: int) -> KernelSet:
    """The kernels of a `dim`-dimensional run (2 or 3)."""
    return KERNELS[dim]
