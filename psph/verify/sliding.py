"""The basal strength of a sliding block: the Drucker-Prager shear strength of a row of
particles at its normal effective stresses, Eq. (14)-(18) of Lian et al. (2023). The
block itself is built and run by the study `bench/studies/sliding.py`."""

import numpy as np


def basal_strength(stress: np.ndarray, eps_p: np.ndarray, dp: np.ndarray) -> np.ndarray:
    """Largest shear stress sigma'_xy the Drucker-Prager surface Eq. (14) allows at the
    normal effective stresses (xx, yy, zz) of each row of `stress`, with the softened
    phi and c of Eq. (17)-(18) (Pa, >= 0)."""
    decay = np.exp(-dp[5] * eps_p)
    phi = dp[1] + (dp[0] - dp[1]) * decay
    c = dp[3] + (dp[2] - dp[3]) * decay
    t = np.tan(phi)
    d = np.sqrt(9.0 + 12.0 * t * t)
    xi, kap = t / d, 3.0 * c / d
    i1 = stress[:, 0] + stress[:, 1] + stress[:, 2]
    m = i1 / 3.0
    s_d2 = 0.5 * ((stress[:, 0] - m) ** 2 + (stress[:, 1] - m) ** 2 + (stress[:, 2] - m) ** 2)
    return np.sqrt(np.clip((kap - xi * i1) ** 2 - s_d2, 0.0, None))
