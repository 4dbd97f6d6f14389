"""Whether a Cartesian Gaussian still holds the spread it stands for.

The CCSP's Gaussian in equinoctial elements holds Monte Carlo members along the orbit for
weeks (docs/mc-vs-ccsp.md, "Weeks"); its Cartesian mean and covariance (what an OEM, a
CDM or a 2-D Pc uses) do not once the along-track arc curves at the scale of the radial
spread: the members lie on a banana no ellipsoid in x, y, z holds. Two measures:

- a CCSP run's **arc sag share** (no members needed): the radial sag of the along-track
  arc, a sigma_lambda^2 / sqrt(2), over the radial 1-sigma of the Cartesian covariance.
  At or above :data:`SAG_SHARE_LIMIT` the Cartesian Gaussian is reported as not holding.
  Chosen on ``benches/ccsp_long.py`` (30 outputs, 1-30 days, six orbits): it flags 11 of
  the 13 outputs where fewer than 90 % of 2,000 members lay inside the Cartesian 95 %
  region, and 3 of the 17 where they did (docs/mc-vs-ccsp.md, "Every run knows").
- a Monte Carlo run's **member coverage**: the share of its members inside the 95 %
  position region of their own moments; below :data:`COVERAGE_FLOOR` it does not hold.
"""

from __future__ import annotations

import numpy as np

#: chi-square 95 % quantile with 3 degrees of freedom (the 3-D position region).
CHI2_3D_95 = 7.814727903251178
#: Arc sag share from which a CCSP's Cartesian Gaussian is reported as not holding.
SAG_SHARE_LIMIT = 0.5
#: Member share inside the 95 % region below which a Monte Carlo's Gaussian summary is
#: reported as not holding: 3.2 binomial sigmas below 95 % at :data:`MIN_MEMBERS`.
COVERAGE_FLOOR = 0.90
#: Fewest members a Monte Carlo output is judged with (:func:`member_coverage`).
MIN_MEMBERS = 200


def arc_sag_share(
    element_mean: np.ndarray, element_covariance: np.ndarray, rtn_covariance: np.ndarray
) -> np.ndarray:
    """Per output (nt,), the along-track arc's radial sag a sigma_lambda^2 / sqrt(2) (m:
    the 1-sigma of r (1 - cos dlambda) for dlambda ~ N(0, sigma_lambda^2)) over the radial
    1-sigma of the Cartesian covariance (whose unscented transform includes the sag): near
    0 the arc is straight at the scale of the spread, near 1 the sag is the radial spread.
    Arguments as a :class:`~rhoprop.CcspResult` holds them: (nt, 6), (nt, 6, 6) equinoctial
    (a in m, lambda in rad) and (nt, 3, 3) RTN m^2. NaN where not finite."""
    a = element_mean[:, 0]
    var_lambda = element_covariance[:, 5, 5]
    radial = rtn_covariance[:, 0, 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = a * var_lambda / np.sqrt(2.0) / np.sqrt(radial)
    return np.where(np.isfinite(share) & (radial > 0), share, np.nan)


def member_coverage(positions: np.ndarray, mean: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """Per output (nt,), the share of Monte Carlo members (positions (n, nt, 3) m, NaN once
    decayed) inside the 95 % position region of the Gaussian ``mean`` (nt, 6),
    ``covariance`` (nt, 6, 6) (their sample moments). NaN where fewer than
    :data:`MIN_MEMBERS` members fly or the position covariance is singular or not finite."""
    nt = positions.shape[1]
    out = np.full(nt, np.nan)
    for t in range(nt):
        alive = np.isfinite(positions[:, t]).all(axis=1)
        pos = covariance[t, :3, :3]
        if (
            alive.sum() < MIN_MEMBERS
            or not np.isfinite(pos).all()
            or not np.isfinite(mean[t]).all()
        ):
            continue
        try:
            inv = np.linalg.inv(pos)
        except np.linalg.LinAlgError:
            continue
        d = positions[alive, t] - mean[t, :3]
        out[t] = float(np.mean(np.einsum("ni,ij,nj->n", d, inv, d) <= CHI2_3D_95))
    return out


def holds(sag_share: np.ndarray | None = None, coverage: np.ndarray | None = None) -> np.ndarray:
    """Per output, whether the Cartesian Gaussian holds the spread: False where the arc
    sag share reaches :data:`SAG_SHARE_LIMIT` or the member coverage is below
    :data:`COVERAGE_FLOOR`; True where neither says so (or neither was measured)."""
    given = sag_share if sag_share is not None else coverage
    if given is None:
        raise ValueError("give sag_share or coverage")
    ok = np.ones(len(given), dtype=bool)
    if sag_share is not None:
        ok &= ~(sag_share >= SAG_SHARE_LIMIT)
    if coverage is not None:
        ok &= ~(coverage < COVERAGE_FLOOR)
    return ok
