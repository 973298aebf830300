"""p = 0 on a drained side's true surface (issue 14, item 3): antisymmetric images across a
free drained plane (`psph/kernels/images.py`), antisymmetric ghosts at a drained wall
(`psph/kernels/ghosts.py`), and the lattice normalisation of the Laplacian of Eq. (23)."""

import numpy as np
import pytest
from helpers import sums_for

from psph.kernels.bundles import (
    GhostSources,
    ImageFields,
    ImageWeights,
    PairFields,
    PairParams,
    WallFields,
    Walls,
)
from psph.kernels.ghosts import make_ghosts
from psph.kernels.images import image_sums, image_weights
from psph.kernels.laplacian import apply_operator, lattice_moment, pair_weights
from psph.kernels.sum_columns import DARCY, DVDT_Y, GP, M_XX, M_YY, MOMENT, SUM_A, SUM_AP, Q

DX = 0.1
H = 1.2 * DX
TOP = 1.0  # the drained plane: the lattice's rows sit at TOP - (k + 1/2) dx


def _column(nx=12, ny=12):
    """A lattice block below the plane y = TOP, rows at TOP - (k + 1/2) dx."""
    gx = (np.arange(nx) + 0.5) * DX
    gy = TOP - (np.arange(ny) + 0.5) * DX
    return np.array(np.meshgrid(gx, gy, indexing="xy")).reshape(2, -1).T


IMAGE_PAR = PairParams(H).typed()  # image_sums reads h, tpi_alpha = 0 and no body force


def _sweep_fields(x, p, vol, perm):
    """The pair sweep's fields with what `image_sums` reads (the others zero)."""
    n = len(x)
    z = np.zeros
    return PairFields(x, z((n, 2)), z((n, 2)), z((n, 4)), p, p.copy(), z(n), vol, z(n), perm,
                      z((n, 2)), z((n, 3)))


def _laplacian(x, p, planes):
    """Eq. (23) with the images of `planes` and the lattice normalisation, as the solver
    takes it: sA, sAp and Q over the recorded pairs, then lap = sAp - p sA - grad p . Q."""
    n = len(x)
    vol = np.full(n, DX * DX)
    pairs = (np.zeros((40 * n, 2), np.int64), np.zeros((40 * n, 2)))
    s, n_pairs = sums_for(x, H, vol, p=p, pairs=pairs)
    image_sums(n, n_pairs, pairs[0], _sweep_fields(x, p, vol, np.ones(n)), planes, IMAGE_PAR, s)
    s[:, DARCY] /= lattice_moment(DX, H)
    m = s[:, MOMENT].reshape(-1, 2, 2)
    grad = np.einsum("in,inm->im", s[:, GP], np.linalg.inv(m))
    return s[:, SUM_AP] - p * s[:, SUM_A] - np.sum(grad * s[:, Q], axis=1)


def test_lattice_moment_is_the_interior_moment_matrix():
    """m0 is M of Eq. (22) of an interior lattice particle (both diagonal entries)."""
    x = _column()
    s = sums_for(x, H, np.full(len(x), DX * DX))
    inner = np.all((x > 3 * H) & (x < 1.2 - 3 * H), axis=1) & (x[:, 1] < TOP - 3 * H)
    assert np.allclose(s[inner, M_XX], lattice_moment(DX, H), rtol=1e-12)
    assert np.allclose(s[inner, M_YY], lattice_moment(DX, H), rtol=1e-12)
    assert lattice_moment(DX, H) == pytest.approx(0.99079, abs=1e-5)


def test_odd_field_has_its_exact_laplacian_up_to_the_drained_plane():
    """p = a s + b s^3 with s = TOP - y vanishes on the plane and its odd extension is the
    same polynomial, so with the images the normalised Eq. (23) gives 6 b s exactly on every
    row, the top row too. Without them the top rows are far off (the plane is not seen)."""
    x = _column()
    s = TOP - x[:, 1]
    p = 3.0 * s + 2.0 * s**3
    planes = np.array([[1.0, TOP, -1.0, 1.0]])
    lap = _laplacian(x, p, planes)
    away = (x[:, 0] > 2 * H) & (x[:, 0] < 1.2 - 2 * H) & (x[:, 1] > 2 * H)
    assert np.allclose(lap[away], 12.0 * s[away], rtol=0, atol=1e-9)
    top = away & (s < DX)
    assert top.sum() > 4
    without = _laplacian(x, p, np.array([[1.0, TOP, -1.0, 0.0]]))  # plane inactive
    assert np.all(np.abs(without[top] - 12.0 * s[top]) > 0.5 * 12.0 * s[top])


def test_images_and_the_plain_laplacian_agree_away_from_the_plane():
    x = _column()
    p = np.sin(3.0 * x[:, 0]) * np.cos(2.0 * x[:, 1])
    planes = np.array([[1.0, TOP, -1.0, 1.0]])
    far = TOP - x[:, 1] > 2 * H  # no image within the support
    assert np.array_equal(_laplacian(x, p, planes)[far],
                          _laplacian(x, p, 0.0 * planes)[far])


def _swept_column(seed: int):
    """An 8 x 8 column under the plane, a random field q on it, the pair sums of q and the
    recorded pairs: (x, vol, q, sums, pairs, grad W of the pairs)."""
    x = _column(8, 8)
    n = len(x)
    vol = np.full(n, DX * DX)
    pairs = (np.zeros((40 * n, 2), np.int64), np.zeros((40 * n, 2)))
    q = np.random.default_rng(seed).normal(size=n)
    s, n_pairs = sums_for(x, H, vol, p=q, pairs=pairs)
    return x, vol, q, s, pairs[0][:n_pairs], pairs[1][:n_pairs]


def test_images_do_not_rely_on_a_rows_pairs_following_one_another():
    """`image_sums` and `image_weights` test a pair's row a against the plane's reach once
    for a run of pairs with the same a (the sweep's order). In the sweep's order and
    shuffled, a far row first or a near one, so that the runs are broken and near and
    far rows alternate, they give what the pairs give one call each (where no run can
    carry a stale test): the same sums to the reordered additions' rounding and the same
    weights pair for pair."""
    x, vol, q, base, pr, g = _swept_column(4)
    n, n_pairs = len(x), len(pr)
    ones = np.ones(n)
    # the top and the left side (x = 0, soil at larger x): each plane's pass starts its
    # runs afresh
    planes = np.array([[1.0, TOP, -1.0, 1.0], [0.0, 0.0, 1.0, 1.0]])
    w = np.zeros(n_pairs)
    pair_weights(n_pairs, pr, g, x, ones, ones, 1.0, 0.0, w)

    def images(m, prs, wts):
        s = np.zeros_like(base)
        image_sums(n, m, prs, _sweep_fields(x, q, vol, ones), planes, IMAGE_PAR, s)
        wd, wo, storage = np.zeros(m), np.zeros(m), np.zeros(n)
        image_weights(n, m, prs, ImageFields(x, ones, ones, vol), planes, H, 1.0, 0.0, wts,
                      ImageWeights(wd, wo, storage))
        return s, wd, wo, storage

    own, _, _, own_storage = images(0, pr[:0], w[:0])
    ref_s = own.copy()
    ref_wd, ref_wo = np.zeros(n_pairs), np.zeros(n_pairs)
    for k in range(n_pairs):  # one pair a call
        s, wd, wo, _ = images(1, pr[k:k + 1], w[k:k + 1])
        ref_s += s - own
        ref_wd[k], ref_wo[k] = wd[0], wo[0]
    assert np.count_nonzero(ref_wd != ref_wo) > 0  # some pairs have an image
    near = (TOP - x[pr[:, 0], 1] < 2 * H) | (x[pr[:, 0], 0] < 2 * H)
    shuffle = np.random.default_rng(5).permutation(n_pairs)
    far_first, near_first = shuffle.copy(), shuffle.copy()
    k_far = int(np.flatnonzero(~near[shuffle])[0])
    k_near = int(np.flatnonzero(near[shuffle])[0])
    far_first[[0, k_far]] = far_first[[k_far, 0]]
    near_first[[0, k_near]] = near_first[[k_near, 0]]
    for order in (np.arange(n_pairs), far_first, near_first):
        s, wd, wo, storage = images(n_pairs, pr[order], w[order])
        back = np.argsort(order)
        assert np.allclose(s, ref_s, rtol=1e-12, atol=1e-12 * np.abs(ref_s).max())
        assert np.array_equal(wd[back], ref_wd) and np.array_equal(wo[back], ref_wo)
        assert np.array_equal(storage, own_storage)
    # the reach itself: an image just inside the support, its row a 1.95 h from the plane
    two = np.array([[0.5, TOP - 1.95 * H], [0.5, TOP - 0.02 * H]])
    for pair in ([[0, 1]], [[1, 0]]):
        wd, wo = np.zeros(1), np.zeros(1)
        image_weights(2, 1, np.array(pair), ImageFields(two, np.ones(2), np.ones(2), np.ones(2)),
                      planes[:1], H, 1.0, 0.0, np.zeros(1), ImageWeights(wd, wo, np.zeros(2)))
        assert wd[0] > 0.0 and wo[0] == -wd[0]


def test_operator_with_images_is_symmetric_positive_definite_and_matches_the_sums():
    """The projection's operator with the images (`image_weights`): symmetric, positive
    definite without storage (the plane pins it), and -S q / V equals the image Laplacian
    of `image_sums` for the same q (without the gradient correction, which the operator
    does not have)."""
    x, vol, q, s, pr, g = _swept_column(3)
    n, n_pairs = len(x), len(pr)
    planes = np.array([[1.0, TOP, -1.0, 1.0]])
    image_sums(n, n_pairs, pr, _sweep_fields(x, q, vol, np.ones(n)), planes, IMAGE_PAR, s)
    w, wd, wo = np.zeros(n_pairs), np.zeros(n_pairs), np.zeros(n_pairs)
    pair_weights(n_pairs, pr, g, x, np.ones(n), np.ones(n), 1.0, 0.0, w)
    storage = np.zeros(n)
    image_weights(n, n_pairs, pr, ImageFields(x, np.ones(n), np.ones(n), vol), planes, H, 1.0,
                  0.0, w, ImageWeights(wd, wo, storage))
    fixed = np.zeros(n, bool)
    S = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1.0
        apply_operator(n, n_pairs, pr, wd, wo, vol, storage, fixed, e, S[:, j])
    assert np.allclose(S, S.T, rtol=0, atol=1e-13 * np.abs(S).max())
    assert np.linalg.eigvalsh(S).min() > 0.0
    assert np.allclose(-(S @ q) / vol, s[:, SUM_AP] - q * s[:, SUM_A], rtol=1e-10, atol=1e-10)


def test_correction_images_pin_the_operator_at_the_plane_before_it_drains():
    """The velocity-correction part of the operator (dt / rho) is imaged across a free
    plane from the start, drained or not: the pair-symmetric correction's self term acts
    as the antisymmetric image of a row's own increment. With the plane not yet drained
    (planes[:, 3] = 0) and no Darcy part, S 1 = 0 away from the plane (no images in the
    support) and S 1 > 0 within 2h of it, and S stays symmetric positive definite."""
    x = _column(8, 8)
    n = len(x)
    vol = np.full(n, DX * DX)
    pairs = (np.zeros((40 * n, 2), np.int64), np.zeros((40 * n, 2)))
    _, n_pairs = sums_for(x, H, vol, pairs=pairs)
    pr, g = pairs[0][:n_pairs], pairs[1][:n_pairs]
    rho, dt = np.full(n, 2000.0), 1e-5
    w, wd, wo = np.zeros(n_pairs), np.zeros(n_pairs), np.zeros(n_pairs)
    pair_weights(n_pairs, pr, g, x, np.ones(n), rho, 0.0, dt, w)
    storage = np.zeros(n)
    planes = np.array([[1.0, TOP, -1.0, 0.0]])
    image_weights(n, n_pairs, pr, ImageFields(x, np.ones(n), rho, vol), planes, H, 1.0, dt, w,
                  ImageWeights(wd, wo, storage))
    S = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = 1.0
        apply_operator(n, n_pairs, pr, wd, wo, vol, storage, np.zeros(n, bool), e, S[:, j])
    row_sum = S @ np.ones(n)
    near = TOP - x[:, 1] < 2 * H
    assert np.allclose(S, S.T, rtol=0, atol=1e-13 * np.abs(S).max())
    assert np.linalg.eigvalsh(S).min() > 0.0
    assert np.all(row_sum[near] > 1e-3 * np.abs(S).max())
    assert np.allclose(row_sum[~near], 0.0, atol=1e-12 * np.abs(S).max())


@pytest.mark.parametrize("drained", [False, True])
def test_drained_wall_ghosts_carry_minus_p(drained):
    """A drained bottom wall mirrors p antisymmetrically (p = 0 on the wall), an impermeable
    one symmetrically plus the hydrostatic shift; a corner ghost across the drained wall
    and an impermeable side wall changes sign once."""
    x0 = np.array([[0.05, 0.05], [0.5, 0.05], [0.5, 0.5]])
    n, cap = len(x0), 32
    z = np.zeros
    x = z((cap, 2))
    x[:n] = x0
    p = z(cap)
    p[:n] = [1.0, 2.0, 3.0]
    p_prev = p.copy()
    v, v_slip, acc = z((cap, 2)), z((cap, 2)), z((cap, 2))
    src, sign = np.zeros(cap, np.int64), np.ones(cap)
    head_b = np.array([0.0, -9810.0])
    walls = Walls(np.array([1, 0]), np.array([0.0, 0.0]), np.array([1.0, 1.0]),
                  np.array([True, False]), np.array([drained, False]))
    f = WallFields(x, v, v_slip, z((cap, 4)), p, p_prev, np.full(cap, 0.4), np.ones(cap),
                   np.ones(cap), np.ones(cap), acc, np.arange(cap, dtype=float))
    ng = make_ghosts(n, cap, 2 * H, 100.0, walls, f, head_b, np.zeros(2),
                     GhostSources(src, sign))
    assert ng == 4  # particle 0: bottom, side, corner; particle 1: bottom
    g = np.arange(n, n + ng)
    bottom = np.isclose(x[g, 1], -0.05) & (x[g, 0] > 0)
    corner = np.isclose(x[g, 1], -0.05) & (x[g, 0] < 0)
    side = np.isclose(x[g, 1], 0.05) & (x[g, 0] < 0)
    if drained:
        assert np.allclose(p[g][bottom], -p[src[g][bottom]])
        assert np.allclose(sign[g][bottom | corner], -1.0) and sign[g][side] == 1.0
        assert p[g][corner] == -p[0] and p[g][side] == p[0]
    else:
        shift = head_b[1] * (-0.1)
        assert np.allclose(p[g][bottom], p[src[g][bottom]] + shift)
        assert np.all(sign[g] == 1.0)


def test_uniform_stress_balances_the_surface_load_with_the_lattice_moment():
    """A column under a surface load q in the uniform state sigma_yy = -q: the pair forces
    of Eq. (26) on the rows under the surface add up to m0 q per column, not q, so the
    load (a force q dx on the top row) left 0.9 % unbalanced and the column carried
    1.004-1.009 q at depth (Terzaghi +0.5 % of q). Divided by m0, as the solver does, they
    balance the load to 1e-3, and every row below the surface layer is free of force."""
    x = _column(12, 12)
    n = len(x)
    q = 1e4
    stress = np.zeros((n, 4))
    stress[:, 1] = -q
    s = sums_for(x, H, np.full(n, DX * DX), stress=stress, rho=np.ones(n))
    force = s[:, DVDT_Y] * DX * DX / lattice_moment(DX, H)  # per particle, rho = 1
    inner = (x[:, 0] > 3 * H) & (x[:, 0] < 1.2 - 3 * H)
    column = inner & np.isclose(x[:, 0], x[inner, 0].min())
    surface = column & (x[:, 1] > TOP - 2 * H)
    assert force[surface].sum() == pytest.approx(q * DX, rel=1e-3)
    assert s[surface, DVDT_Y].sum() * DX * DX == pytest.approx(lattice_moment(DX, H) * q * DX,
                                                             rel=1e-3)
    below = column & (x[:, 1] < TOP - 2 * H) & (x[:, 1] > 3 * H)
    assert np.allclose(force[below], 0.0, atol=1e-9 * q * DX)
