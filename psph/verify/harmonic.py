"""Reference for the 1D harmonic consolidation of Section 4.2: the same (u - p_l)
equations on a 1D grid, without particles.

Depth z from the top (0) to the fixed bottom (L), u and v downward positive, compression
positive stresses. Momentum (Eq. 6 in 1D, with the global damping force of Eq. 43):
    rho dv/dt = -d(sigma'_c + p)/dz - c_d rho v,   sigma'_c = -M du/dz,
with the total traction q(t) = q0 (1 - cos omega t) at the top. Pore pressure (Eq. 10 in
1D, quasi-static fluid): (n/K_l) dp/dt = -dv/dz + (k/gamma_l) d2p/dz2, p = 0 at the top
(drained), no flux at the bottom. Staggered grid: u, v at nodes, p and sigma' at cell
centres; v explicit (symplectic Euler), p backward Euler (tridiagonal solve), so the only
limit is the undrained wave speed sqrt((M + K_l/n)/rho).

With c_d = 0 this is the physical problem; with the scene's c_d it is exactly what the
SPH model integrates, so the difference is the particle discretisation error.
"""

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from psph.physics.material import soil_from_scene


@nb.njit(cache=True)
def _integrate(nz, dz, dt, nsteps, every, rho, modulus, storage, kg, damping, q0, omega,
               p_out, u_out, t_out):
    u = np.zeros(nz + 1)
    v = np.zeros(nz + 1)
    p = np.zeros(nz)
    a = np.zeros(nz)
    b = np.zeros(nz)
    c = np.zeros(nz)
    d = np.zeros(nz)
    r = kg * dt / (dz * dz)
    for i in range(nz):
        a[i] = -r
        c[i] = -r
        b[i] = storage + 2.0 * r
    b[0] = storage + 3.0 * r  # p = 0 on the top face: ghost value -p_0
    b[nz - 1] = storage + r  # no flux at the bottom
    cp = np.zeros(nz)
    k_out = 0
    t = 0.0
    for step in range(nsteps + 1):
        if step % every == 0:
            p_out[k_out, :] = p
            u_out[k_out, :] = u
            t_out[k_out] = t
            k_out += 1
        if step == nsteps:
            break
        q = q0 * (1.0 - math.cos(omega * t))
        # momentum at nodes 0..nz-1 (node nz is fixed)
        for i in range(nz):
            s_below = -modulus * (u[i + 1] - u[i]) / dz + p[i]
            if i == 0:
                force = (q - s_below) / (0.5 * dz)
            else:
                s_above = -modulus * (u[i] - u[i - 1]) / dz + p[i - 1]
                force = (s_above - s_below) / dz
            v[i] += dt * (force / rho - damping * v[i])
        for i in range(nz):
            u[i] += dt * v[i]
        # pressure, backward Euler: storage (p' - p) = -dt dv/dz + r (p'_+ - 2p' + p'_-)
        for i in range(nz):
            d[i] = storage * p[i] - dt * (v[i + 1] - v[i]) / dz
        cp[0] = c[0] / b[0]
        d[0] = d[0] / b[0]
        for i in range(1, nz):
            m = b[i] - a[i] * cp[i - 1]
            cp[i] = c[i] / m
            d[i] = (d[i] - a[i] * d[i - 1]) / m
        p[nz - 1] = d[nz - 1]
        for i in range(nz - 2, -1, -1):
            p[i] = d[i] - cp[i] * p[i + 1]
        t += dt


@dataclass(frozen=True)
class HarmonicColumn:
    """The 1D problem; `solve` returns (t, z of cell centres, p(t, z), u(t, nodes))."""

    height: float
    modulus: float  # constrained modulus M (Pa)
    density: float  # mixture density (kg/m^3)
    porosity: float
    bulk_water: float
    conductivity: float
    gamma_l: float
    load: float  # q0 (Pa)
    omega: float  # rad/s
    damping: float = 0.0  # c_d (1/s)

    def solve(self, end: float, out_interval: float, nz: int = 1000):
        dz = self.height / nz
        c_u = math.sqrt((self.modulus + self.bulk_water / self.porosity) / self.density)
        dt0 = 0.4 * dz / c_u
        every = max(int(math.ceil(out_interval / dt0)), 1)
        dt = out_interval / every
        nsteps = int(round(end / dt))
        nout = nsteps // every + 1
        p_out = np.zeros((nout, nz))
        u_out = np.zeros((nout, nz + 1))
        t_out = np.zeros(nout)
        _integrate(nz, dz, dt, nsteps, every, self.density, self.modulus,
                   self.porosity / self.bulk_water, self.conductivity / self.gamma_l,
                   self.damping, self.load, self.omega, p_out, u_out, t_out)
        z = (np.arange(nz) + 0.5) * dz
        return t_out, z, p_out, u_out

    def pressure_at(self, depths, end: float, out_interval: float, nz: int = 1000):
        """(t, p[t, depth]) at the given depths, linear in z between cell centres."""
        t, z, p, _ = self.solve(end, out_interval, nz)
        return t, np.stack([np.interp(depths, z, row) for row in p])


def from_scene(scene, damped: bool) -> HarmonicColumn:
    soil = soil_from_scene(scene)
    load = scene.loads[0]
    top = max(b.max[1] for b in scene.particles.blocks)
    bottom = min(b.min[1] for b in scene.particles.blocks)
    c_d = soil.damping_coefficient(scene.stabilisation.damping, scene.h) if damped else 0.0
    return HarmonicColumn(height=top - bottom, modulus=soil.constrained_modulus,
                          density=soil.mixture_density, porosity=soil.porosity,
                          bulk_water=soil.K_l, conductivity=soil.conductivity,
                          gamma_l=soil.gamma_l, load=load.pressure, omega=load.omega,
                          damping=c_d)
