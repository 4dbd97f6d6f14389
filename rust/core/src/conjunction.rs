//! Probability of collision (Pc) of two objects at their time of closest approach.
//!
//! - [`pc_2d`]: the short-encounter ("2-D", Foster/Alfano) Pc. Relative position
//!   r = r2 - r1 and velocity v = v2 - v1 define the encounter frame yhat = v/|v|,
//!   zhat = (r x v)/|r x v|, xhat = yhat x zhat; the combined position covariance
//!   C = C1 + C2 is projected on the encounter plane, P C P^T with P = [xhat; zhat], and
//!   the 2-D Gaussian N(u; 0, P C P^T) is integrated over the hard-body region centred on
//!   the miss vector (|r_perp|, 0): a circle of radius HBR, a square of half-side HBR, or
//!   the square of the circle's area (half-side sqrt(pi)/2 HBR), squares aligned with the
//!   encounter-frame axes.
//! - [`pc_pairs`]: the Monte Carlo estimate from member states of both objects: the
//!   fraction of all n1 n2 member pairs whose straight-line relative motion passes within
//!   HBR, a two-sample U-statistic, with its variance.
//!
//! The integral is exact up to quadrature error (adaptive Gauss-Legendre, relative
//! tolerance 1e-10): the circle is integrated in the principal axes of the projected
//! covariance as a 1-D integral of differences of normal distribution functions (erfc)
//! over the axis of the smaller standard deviation, parametrised by the angle around the
//! circle so the square-root end points are smooth; the squares as a 1-D integral of the
//! conditional normal (a product of erf differences when the axes are uncorrelated).
//!
//! A projected covariance that is not positive definite is repaired as NASA CARA does it
//! (eigenvalue clipping: eigenvalues below (1e-4 HBR)^2 raised to that floor, a larger
//! CARA factor where the rebuilt matrix would still fail the Cholesky test) and
//! reported, or refused ([`NpdPolicy`]).

use crate::error::{finite, positive, CoreError};
use crate::frames::{cross, dot, norm};
use crate::progress::Progress;
use rayon::prelude::*;
use std::f64::consts::{FRAC_1_SQRT_2, PI};
use std::sync::OnceLock;

/// Shape of the hard-body region in the encounter plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HardBodyShape {
    /// Disc of radius HBR.
    Circle,
    /// Square of half-side HBR, sides along the encounter-frame x and z axes.
    Square,
    /// Square of the disc's area: half-side sqrt(pi)/2 HBR, same orientation.
    SquareEqualArea,
}

impl HardBodyShape {
    /// The names the binding accepts, in the order of the variants.
    pub const NAMES: &'static [&'static str] = &["circle", "square", "square_equal_area"];

    /// The shape from its name.
    pub fn from_name(name: &str) -> Result<Self, CoreError> {
        match name {
            "circle" => Ok(Self::Circle),
            "square" => Ok(Self::Square),
            "square_equal_area" => Ok(Self::SquareEqualArea),
            other => Err(CoreError::UnknownName {
                what: "hard-body shape",
                name: other.to_string(),
                expected: Self::NAMES,
            }),
        }
    }
}

/// What to do with a projected (2x2) covariance that is not positive definite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NpdPolicy {
    /// Clip its eigenvalues to (1e-4 HBR)^2 as CARA does, and report it.
    Repair,
    /// Return an error.
    Raise,
}

impl NpdPolicy {
    /// The names the binding accepts.
    pub const NAMES: &'static [&'static str] = &["repair", "raise"];

    /// The policy from its name.
    pub fn from_name(name: &str) -> Result<Self, CoreError> {
        match name {
            "repair" => Ok(Self::Repair),
            "raise" => Ok(Self::Raise),
            other => Err(CoreError::UnknownName {
                what: "non-positive-definite policy",
                name: other.to_string(),
                expected: Self::NAMES,
            }),
        }
    }
}

/// CARA's eigenvalue clipping factors, smallest (the standard one) first: the
/// eigenvalues of a non-positive-definite projected covariance are raised to
/// (factor * HBR)^2 with the first factor whose rebuilt matrix passes the Cholesky test
/// (a larger one is needed only where the eigenvalues span more than double precision).
pub const CLIP_FACTORS: [f64; 6] = [1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2];

/// Whether a symmetric 2x2 matrix passes both Cholesky pivot tests.
fn cholesky_ok(c: &[[f64; 2]; 2]) -> bool {
    c[0][0] > 0.0 && c[1][1] - c[0][1] * c[0][1] / c[0][0] > 0.0
}

/// CARA's remediation of a non-positive-definite 2x2 covariance: eigenvalues clipped to
/// (factor * HBR)^2 with the smallest of [`CLIP_FACTORS`] whose rebuilt matrix is
/// positive definite. Returns the matrix and its eigen-decomposition, or None.
fn remediate(eig: &Eigen2, hbr: f64) -> Option<([[f64; 2]; 2], Eigen2)> {
    CLIP_FACTORS.iter().find_map(|f| {
        let floor = (f * hbr).powi(2);
        let clipped = Eigen2 {
            l1: eig.l1.max(floor),
            l2: eig.l2.max(floor),
            e1: eig.e1,
        };
        let m = clipped.matrix();
        let fresh = Eigen2::of(&m);
        (cholesky_ok(&m) && fresh.positive_definite()).then_some((m, fresh))
    })
}

/// The encounter geometry of a conjunction.
#[derive(Debug, Clone, PartialEq)]
pub struct Encounter {
    /// Encounter-frame axes as rows: xhat (along the miss), yhat (along the relative
    /// velocity), zhat (along r x v).
    pub axes: [[f64; 3]; 3],
    /// Miss vector in the encounter plane (x, z), m: (|r_perp|, 0).
    pub miss: [f64; 2],
    /// |r_perp|, the straight-line miss distance, m.
    pub miss_distance: f64,
    /// |v2 - v1|, m/s.
    pub relative_speed: f64,
    /// Combined position covariance projected on the plane, [[xx, xz], [xz, zz]], m^2.
    pub covariance: [[f64; 2]; 2],
}

/// The 2-D Pc and what it was computed from.
#[derive(Debug, Clone, PartialEq)]
pub struct Pc2d {
    /// Probability of collision.
    pub pc: f64,
    /// The encounter geometry; its covariance is the projected one before any repair.
    pub encounter: Encounter,
    /// The 2x2 covariance integrated (after repair), m^2.
    pub covariance: [[f64; 2]; 2],
    /// Whether the projected covariance was not positive definite and was repaired.
    pub repaired: bool,
}

fn check_vec(name: &str, v: [f64; 3]) -> Result<(), CoreError> {
    for (i, x) in v.iter().enumerate() {
        finite(&format!("{name}[{i}]"), *x)?;
    }
    Ok(())
}

fn check_cov(name: &str, c: &[[f64; 3]; 3]) -> Result<(), CoreError> {
    for (i, row) in c.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            finite(&format!("{name}[{i}][{j}]"), *x)?;
        }
    }
    Ok(())
}

fn unit(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    [a[0] / n, a[1] / n, a[2] / n]
}

/// A unit vector perpendicular to the unit vector `y` (through the coordinate axis least
/// aligned with it): the encounter-frame z axis when r is parallel to v.
fn perpendicular(y: [f64; 3]) -> [f64; 3] {
    let mut k = 0;
    for i in 1..3 {
        if y[i].abs() < y[k].abs() {
            k = i;
        }
    }
    let mut e = [0.0; 3];
    e[k] = 1.0;
    unit(cross(y, e))
}

/// The encounter frame, miss vector and projected combined covariance of object 1
/// (`r1` m, `v1` m/s, position covariance `cov1` m^2) and object 2, all inertial.
///
/// Errors for non-finite inputs and for zero relative velocity. Where r is parallel to v
/// (including a miss of exactly 0) zhat is any unit vector perpendicular to v (chosen
/// deterministically); the circle Pc does not depend on that choice.
pub fn encounter(
    r1: [f64; 3],
    v1: [f64; 3],
    cov1: &[[f64; 3]; 3],
    r2: [f64; 3],
    v2: [f64; 3],
    cov2: &[[f64; 3]; 3],
) -> Result<Encounter, CoreError> {
    check_vec("r1", r1)?;
    check_vec("v1", v1)?;
    check_vec("r2", r2)?;
    check_vec("v2", v2)?;
    check_cov("cov1", cov1)?;
    check_cov("cov2", cov2)?;
    let r = [r2[0] - r1[0], r2[1] - r1[1], r2[2] - r1[2]];
    let v = [v2[0] - v1[0], v2[1] - v1[1], v2[2] - v1[2]];
    let speed = norm(v);
    if !speed.is_finite() {
        return Err(CoreError::non_finite("relative speed |v2 - v1|", speed));
    }
    if speed == 0.0 {
        return Err(CoreError::invalid(
            "relative speed |v2 - v1|",
            0.0,
            "the objects have the same velocity; the short-encounter Pc needs relative motion",
        ));
    }
    let y = [v[0] / speed, v[1] / speed, v[2] / speed];
    let h = cross(r, y);
    // r parallel to v (within rounding) leaves r x v without a direction.
    let z = if norm(h) > 1e-14 * norm(r) && norm(h) > 0.0 {
        unit(h)
    } else {
        perpendicular(y)
    };
    let x = cross(y, z);
    let miss = [dot(r, x), dot(r, z)];
    let c: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| cov1[i][j] + cov2[i][j]));
    // Symmetrised projection P C P^T, P = [x; z].
    let quad = |a: [f64; 3], b: [f64; 3]| -> f64 {
        let mut s = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                s += a[i] * 0.5 * (c[i][j] + c[j][i]) * b[j];
            }
        }
        s
    };
    let xz = quad(x, z);
    Ok(Encounter {
        axes: [x, y, z],
        miss,
        miss_distance: miss[0].hypot(miss[1]),
        relative_speed: speed,
        covariance: [[quad(x, x), xz], [xz, quad(z, z)]],
    })
}

/// Eigen-decomposition of a symmetric 2x2 matrix.
#[derive(Debug, Clone, Copy)]
struct Eigen2 {
    /// Larger and smaller eigenvalue.
    l1: f64,
    l2: f64,
    /// Unit eigenvector of l1; that of l2 is (-e1[1], e1[0]).
    e1: [f64; 2],
}

impl Eigen2 {
    fn of(c: &[[f64; 2]; 2]) -> Self {
        let (a, b, d) = (c[0][0], c[0][1], c[1][1]);
        let mean = 0.5 * (a + d);
        let rad = (0.5 * (a - d)).hypot(b);
        let l1 = mean + rad;
        let mut l2 = mean - rad;
        // The smaller eigenvalue through the determinant where that is more accurate.
        if l1 > 0.0 && mean > 0.0 {
            let det = a * d - b * b;
            if det > 0.0 {
                l2 = det / l1;
            }
        }
        let phi = 0.5 * (2.0 * b).atan2(a - d);
        Eigen2 {
            l1,
            l2,
            e1: [phi.cos(), phi.sin()],
        }
    }

    fn e2(&self) -> [f64; 2] {
        [-self.e1[1], self.e1[0]]
    }

    fn matrix(&self) -> [[f64; 2]; 2] {
        let (e1, e2) = (self.e1, self.e2());
        std::array::from_fn(|i| {
            std::array::from_fn(|j| self.l1 * e1[i] * e1[j] + self.l2 * e2[i] * e2[j])
        })
    }

    fn positive_definite(&self) -> bool {
        self.l1 > 0.0 && self.l2 > 0.0
    }
}

/// Standard normal density.
fn npdf(x: f64) -> f64 {
    const INV_SQRT_2PI: f64 = 0.398_942_280_401_432_7;
    INV_SQRT_2PI * (-0.5 * x * x).exp()
}

/// Standard normal upper tail P(Z > x), accurate to ~1e-15 relative everywhere.
fn upper_tail(x: f64) -> f64 {
    0.5 * libm::erfc(x * FRAC_1_SQRT_2)
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut t = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, t);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (t * p1 - p0) / (t * t - 1.0);
            let step = p1 / dp;
            t -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        x[i] = -t;
        x[n - 1 - i] = t;
        let wi = 2.0 / ((1.0 - t * t) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    (x, w)
}

/// Nodes of the rule each adaptive panel uses.
const PANEL_NODES: usize = 20;
/// Nodes of the rule for a narrow normal probability.
const NARROW_NODES: usize = 10;

fn rule(n: usize) -> &'static (Vec<f64>, Vec<f64>) {
    static PANEL: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    static NARROW: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    match n {
        PANEL_NODES => PANEL.get_or_init(|| gauss_legendre(PANEL_NODES)),
        _ => NARROW.get_or_init(|| gauss_legendre(NARROW_NODES)),
    }
}

fn fixed_rule(f: &dyn Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let (x, w) = rule(n);
    let (c, h) = (0.5 * (a + b), 0.5 * (b - a));
    h * x
        .iter()
        .zip(w)
        .map(|(xi, wi)| wi * f(c + h * xi))
        .sum::<f64>()
}

/// P(lo < Z < hi) for a standard normal Z and lo <= hi, to ~1e-15 relative also far in
/// the tails and for narrow intervals (no cancellation of two close erfc values).
fn normal_prob(lo: f64, hi: f64) -> f64 {
    if hi <= lo {
        return 0.0;
    }
    let width = hi - lo;
    let mid = 0.5 * (lo + hi);
    if width.is_finite() && width * (1.0 + mid.abs()) <= 1.0 {
        // The density varies by less than e over the interval: a 10-point rule is exact
        // to rounding.
        return fixed_rule(&npdf, lo, hi, NARROW_NODES);
    }
    if lo >= 0.0 {
        upper_tail(lo) - upper_tail(hi)
    } else if hi <= 0.0 {
        upper_tail(-hi) - upper_tail(-lo)
    } else {
        1.0 - upper_tail(hi) - upper_tail(-lo)
    }
}

/// Relative tolerance of the adaptive quadrature.
const REL_TOL: f64 = 1e-10;
/// Absolute tolerance (probabilities below this are of no interest).
const ABS_TOL: f64 = 1e-40;
/// Most panels the adaptive quadrature splits an integral into.
const MAX_PANELS: usize = 4000;

struct Panel {
    a: f64,
    b: f64,
    left: f64,
    right: f64,
    err: f64,
}

impl Panel {
    fn new(f: &dyn Fn(f64) -> f64, a: f64, b: f64, whole: f64) -> Self {
        let m = 0.5 * (a + b);
        let left = fixed_rule(f, a, m, PANEL_NODES);
        let right = fixed_rule(f, m, b, PANEL_NODES);
        Panel {
            a,
            b,
            left,
            right,
            err: (whole - (left + right)).abs(),
        }
    }
}

/// Integral of `f` over [breaks[0], breaks[last]] (breaks sorted, inner ones where `f`
/// changes fast): globally adaptive, each panel estimated by the 20-point Gauss-Legendre
/// rule on its halves and its error by the difference to the rule on the whole panel;
/// the panel with the largest error is halved until the summed error is below
/// REL_TOL * |integral| (or ABS_TOL).
fn integrate(f: &dyn Fn(f64) -> f64, breaks: &[f64]) -> f64 {
    let mut panels: Vec<Panel> = breaks
        .windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| Panel::new(f, w[0], w[1], fixed_rule(f, w[0], w[1], PANEL_NODES)))
        .collect();
    loop {
        let total: f64 = panels.iter().map(|p| p.left + p.right).sum();
        let err: f64 = panels.iter().map(|p| p.err).sum();
        if err <= REL_TOL * total.abs() || err <= ABS_TOL || panels.len() >= MAX_PANELS {
            return total;
        }
        let (k, _) = panels.iter().enumerate().fold((0, -1.0), |best, (i, p)| {
            if p.err > best.1 {
                (i, p.err)
            } else {
                best
            }
        });
        let p = panels.swap_remove(k);
        let m = 0.5 * (p.a + p.b);
        if !(m > p.a && m < p.b) {
            // Cannot be halved further in floating point.
            panels.push(Panel { err: 0.0, ..p });
            continue;
        }
        panels.push(Panel::new(f, p.a, m, p.left));
        panels.push(Panel::new(f, m, p.b, p.right));
    }
}

/// Standard deviations beyond which the Gaussian's mass (< 4e-33) is left out.
const TAIL: f64 = 12.0;

/// Sorted break points: the ends plus those of `inner` strictly between them.
fn breakpoints(lo: f64, hi: f64, inner: &[f64]) -> Vec<f64> {
    let mut b = vec![lo, hi];
    b.extend(inner.iter().copied().filter(|t| *t > lo && *t < hi));
    b.sort_by(f64::total_cmp);
    b
}

/// Integral of N(u; 0, C) over the disc |u - miss| <= radius, C given by its
/// eigen-decomposition (both eigenvalues > 0).
fn circle_probability(miss: [f64; 2], eig: &Eigen2, radius: f64) -> f64 {
    let (s_major, s_minor) = (eig.l1.sqrt(), eig.l2.sqrt());
    // Outer variable x along the minor axis (the Gaussian is narrowest there), inner along
    // the major axis, where it is integrated in closed form.
    let (e1, e2) = (eig.e1, eig.e2());
    let p = miss[0] * e2[0] + miss[1] * e2[1];
    let q = miss[0] * e1[0] + miss[1] * e1[1];
    // x = p + radius sin(theta); chord half-length radius cos(theta).
    let lo = ((-TAIL * s_minor - p) / radius).max(-1.0);
    let hi = ((TAIL * s_minor - p) / radius).min(1.0);
    if lo >= hi {
        return 0.0;
    }
    let f = |theta: f64| {
        let (s, c) = theta.sin_cos();
        let half = radius * c;
        let x = p + radius * s;
        half * npdf(x / s_minor) / s_minor * normal_prob((q - half) / s_major, (q + half) / s_major)
    };
    let mut inner = Vec::with_capacity(3);
    if p.abs() < radius {
        inner.push((-p / radius).asin()); // x = 0: the Gaussian's centre line
    }
    if q.abs() < radius {
        let t = (q.abs() / radius).acos(); // chord ends cross the major axis
        inner.push(t);
        inner.push(-t);
    }
    integrate(&f, &breakpoints(lo.asin(), hi.asin(), &inner))
}

/// Integral of N(u; 0, C) over the rectangle |u_x - miss_x| <= half, |u_z - miss_z| <= half.
fn square_probability(miss: [f64; 2], c: &[[f64; 2]; 2], det: f64, half: f64) -> f64 {
    let (cxx, cxz, czz) = (c[0][0], c[0][1], c[1][1]);
    if cxz == 0.0 {
        let (sx, sz) = (cxx.sqrt(), czz.sqrt());
        return normal_prob((miss[0] - half) / sx, (miss[0] + half) / sx)
            * normal_prob((miss[1] - half) / sz, (miss[1] + half) / sz);
    }
    // Outer variable: the axis of smaller variance.
    let (var_o, m_o, m_i) = if cxx <= czz {
        (cxx, miss[0], miss[1])
    } else {
        (czz, miss[1], miss[0])
    };
    let s_o = var_o.sqrt();
    let slope = cxz / var_o;
    let s_cond = (det / var_o).sqrt();
    let lo = (m_o - half).max(-TAIL * s_o);
    let hi = (m_o + half).min(TAIL * s_o);
    if lo >= hi {
        return 0.0;
    }
    let f = |x: f64| {
        let mu = slope * x;
        npdf(x / s_o) / s_o * normal_prob((m_i - half - mu) / s_cond, (m_i + half - mu) / s_cond)
    };
    let inner = [0.0, (m_i - half) / slope, (m_i + half) / slope];
    integrate(&f, &breakpoints(lo, hi, &inner))
}

/// Integral of N(u; 0, `covariance`) (2x2, m^2, positive definite or repaired per `npd`)
/// over the hard-body region of `shape` and radius `hbr` (m) centred on `miss` (m).
/// Returns (Pc, the covariance integrated, whether it was repaired).
pub fn encounter_plane_pc(
    miss: [f64; 2],
    covariance: &[[f64; 2]; 2],
    hbr: f64,
    shape: HardBodyShape,
    npd: NpdPolicy,
) -> Result<(f64, [[f64; 2]; 2], bool), CoreError> {
    positive("hard_body_radius", hbr)?;
    for (i, m) in miss.iter().enumerate() {
        finite(&format!("miss[{i}]"), *m)?;
    }
    for i in 0..2 {
        for j in 0..2 {
            finite(&format!("covariance[{i}][{j}]"), covariance[i][j])?;
        }
    }
    let sym = 0.5 * (covariance[0][1] + covariance[1][0]);
    let c = [[covariance[0][0], sym], [sym, covariance[1][1]]];
    let mut eig = Eigen2::of(&c);
    let pd = eig.positive_definite() && cholesky_ok(&c);
    let (c, repaired) = if pd {
        (c, false)
    } else {
        match npd {
            NpdPolicy::Raise => {
                return Err(CoreError::rejected(
                    "encounter-plane covariance",
                    format!(
                        "the combined position covariance projected on the encounter plane \
                         is not positive definite (eigenvalues {:e} and {:e} m^2); pass \
                         npd=\"repair\" to clip its eigenvalues as NASA CARA does",
                        eig.l1, eig.l2
                    ),
                ))
            }
            NpdPolicy::Repair => {
                let (fixed, fixed_eig) = remediate(&eig, hbr).ok_or_else(|| {
                    CoreError::rejected(
                        "encounter-plane covariance",
                        format!(
                            "the combined position covariance projected on the encounter \
                             plane is not positive definite (eigenvalues {:e} and {:e} m^2) \
                             and eigenvalue clipping up to ({:e} HBR)^2 could not repair it",
                            eig.l1,
                            eig.l2,
                            CLIP_FACTORS[CLIP_FACTORS.len() - 1]
                        ),
                    )
                })?;
                eig = fixed_eig;
                (fixed, true)
            }
        }
    };
    let pc = match shape {
        HardBodyShape::Circle => circle_probability(miss, &eig, hbr),
        HardBodyShape::Square => square_probability(miss, &c, eig.l1 * eig.l2, hbr),
        HardBodyShape::SquareEqualArea => {
            square_probability(miss, &c, eig.l1 * eig.l2, 0.5 * PI.sqrt() * hbr)
        }
    };
    // Quadrature rounding can leave a hair above 1 or below 0.
    Ok((pc.clamp(0.0, 1.0), c, repaired))
}

/// The short-encounter 2-D probability of collision of object 1 (position `r1` m,
/// velocity `v1` m/s, position covariance `cov1` m^2) and object 2, all in one inertial
/// frame at the time of closest approach, for a combined hard-body radius `hbr` m.
///
/// Errors: non-finite input, zero relative velocity, `hbr` <= 0, a projected covariance
/// that is not positive definite under [`NpdPolicy::Raise`].
#[allow(clippy::too_many_arguments)]
pub fn pc_2d(
    r1: [f64; 3],
    v1: [f64; 3],
    cov1: &[[f64; 3]; 3],
    r2: [f64; 3],
    v2: [f64; 3],
    cov2: &[[f64; 3]; 3],
    hbr: f64,
    shape: HardBodyShape,
    npd: NpdPolicy,
) -> Result<Pc2d, CoreError> {
    positive("hard_body_radius", hbr)?;
    let enc = encounter(r1, v1, cov1, r2, v2, cov2)?;
    let (pc, covariance, repaired) =
        encounter_plane_pc(enc.miss, &enc.covariance, hbr, shape, npd)?;
    Ok(Pc2d {
        pc,
        encounter: enc,
        covariance,
        repaired,
    })
}

/// The Monte Carlo Pc over all member pairs.
#[derive(Debug, Clone, PartialEq)]
pub struct PairCount {
    /// Pairs (i, j) whose straight-line miss is <= HBR.
    pub hits: u64,
    /// n1 * n2.
    pub pairs: u64,
    /// hits / pairs: the two-sample U-statistic estimate of Pc.
    pub pc: f64,
    /// Its variance estimate s10^2 / n1 + s01^2 / n2, where s10^2 is the sample variance
    /// (ddof = 1) over i of the row hit fractions and s01^2 that over j of the columns.
    pub variance: f64,
}

/// Rows of members of object 1 handled by one parallel task.
const ROWS_PER_TASK: usize = 64;

fn check_members(name: &str, m: &[[f64; 6]]) -> Result<(), CoreError> {
    if m.len() < 2 {
        return Err(CoreError::shape(
            name,
            format!("needs at least 2 members for a variance, got {}", m.len()),
        ));
    }
    for (i, row) in m.iter().enumerate() {
        for (k, x) in row.iter().enumerate() {
            finite(&format!("{name}[{i}][{k}]"), *x)?;
        }
    }
    Ok(())
}

/// Whether the straight-line relative motion of a pair passes within `hbr`: the distance
/// |r - (r . vhat) vhat| of the pair's relative position r = r2 - r1 from the line of its
/// relative velocity v = v2 - v1 (|r| where v = 0, the separation never changing).
fn pair_hits(a: &[f64; 6], b: &[f64; 6], hbr2: f64) -> bool {
    let r = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [b[3] - a[3], b[4] - a[4], b[5] - a[5]];
    let vv = dot(v, v);
    let rr = dot(r, r);
    if vv == 0.0 {
        return rr <= hbr2;
    }
    let s = dot(r, v) / vv;
    let p = [r[0] - s * v[0], r[1] - s * v[1], r[2] - s * v[2]];
    dot(p, p) <= hbr2
}

/// Sample variance (ddof = 1) of counts / scale, exact up to the final division.
fn count_variance(counts: &[u64], scale: f64) -> f64 {
    let n = counts.len() as u128;
    let sum: u128 = counts.iter().map(|&c| c as u128).sum();
    let sum2: u128 = counts.iter().map(|&c| (c as u128) * (c as u128)).sum();
    let num = n * sum2 - sum * sum; // n^2 times the biased variance, >= 0
    num as f64 / ((n * (n - 1)) as f64 * scale * scale)
}

/// Monte Carlo Pc from member states (position m, velocity m/s, inertial, at or near the
/// time of closest approach) of object 1 (`members1`, n1 x 6) and object 2 (n2 x 6): the
/// fraction of all n1 n2 pairs (i, j) whose straight-line relative motion passes within
/// `hbr`. Rayon-parallel over rows; integer counts make it identical for any thread count.
/// `progress` counts the members of object 1 done and cancels the count when asked.
pub fn pc_pairs(
    members1: &[[f64; 6]],
    members2: &[[f64; 6]],
    hbr: f64,
    progress: &Progress,
) -> Result<PairCount, CoreError> {
    positive("hard_body_radius", hbr)?;
    check_members("members1", members1)?;
    check_members("members2", members2)?;
    let hbr2 = hbr * hbr;
    let n2 = members2.len();
    let chunks: Vec<(Vec<u64>, Vec<u64>)> = members1
        .par_chunks(ROWS_PER_TASK)
        .map(|rows| {
            progress.check()?;
            let mut row_counts = Vec::with_capacity(rows.len());
            let mut col_counts = vec![0u64; n2];
            for a in rows {
                let mut c = 0u64;
                for (j, b) in members2.iter().enumerate() {
                    if pair_hits(a, b, hbr2) {
                        c += 1;
                        col_counts[j] += 1;
                    }
                }
                row_counts.push(c);
            }
            progress.add(rows.len());
            Ok((row_counts, col_counts))
        })
        .collect::<Result<_, CoreError>>()?;
    let mut rows = Vec::with_capacity(members1.len());
    let mut cols = vec![0u64; n2];
    for (r, c) in chunks {
        rows.extend(r);
        for (acc, x) in cols.iter_mut().zip(c) {
            *acc += x;
        }
    }
    let hits: u64 = rows.iter().sum();
    let pairs = (members1.len() as u64) * (n2 as u64);
    let variance = count_variance(&rows, n2 as f64) / members1.len() as f64
        + count_variance(&cols, members1.len() as f64) / n2 as f64;
    Ok(PairCount {
        hits,
        pairs,
        pc: hits as f64 / pairs as f64,
        variance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const I3: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    fn scaled(c: [[f64; 3]; 3], s: f64) -> [[f64; 3]; 3] {
        c.map(|row| row.map(|x| x * s))
    }

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// Brute-force reference: the disc in polar coordinates around the miss point, with
    /// tensor Gauss-Legendre rules (radius and angle, each cut into panels).
    fn polar_reference(miss: [f64; 2], c: [[f64; 2]; 2], radius: f64) -> f64 {
        let det = c[0][0] * c[1][1] - c[0][1] * c[0][1];
        let inv = [
            [c[1][1] / det, -c[0][1] / det],
            [-c[0][1] / det, c[0][0] / det],
        ];
        let (x, w) = gauss_legendre(40);
        let (nr, nt) = (40, 80);
        let mut total = 0.0;
        for pr in 0..nr {
            let (r0, r1) = (
                radius * pr as f64 / nr as f64,
                radius * (pr + 1) as f64 / nr as f64,
            );
            for pt in 0..nt {
                let (t0, t1) = (
                    2.0 * PI * pt as f64 / nt as f64,
                    2.0 * PI * (pt + 1) as f64 / nt as f64,
                );
                for (xi, wi) in x.iter().zip(&w) {
                    let rho = 0.5 * (r0 + r1) + 0.5 * (r1 - r0) * xi;
                    for (xj, wj) in x.iter().zip(&w) {
                        let th = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * xj;
                        let u = [miss[0] + rho * th.cos(), miss[1] + rho * th.sin()];
                        let q = u[0] * (inv[0][0] * u[0] + inv[0][1] * u[1])
                            + u[1] * (inv[1][0] * u[0] + inv[1][1] * u[1]);
                        let dens = (-0.5 * q).exp() / (2.0 * PI * det.sqrt());
                        total += wi * wj * 0.25 * (r1 - r0) * (t1 - t0) * rho * dens;
                    }
                }
            }
        }
        total
    }

    #[test]
    fn legendre_rule_integrates_polynomials() {
        let (x, w) = gauss_legendre(PANEL_NODES);
        let s: f64 = w.iter().sum();
        assert!((s - 2.0).abs() < 1e-14);
        // x^38 is integrated exactly by 20 nodes: 2/39.
        let m: f64 = x.iter().zip(&w).map(|(xi, wi)| wi * xi.powi(38)).sum();
        assert!(rel(m, 2.0 / 39.0) < 1e-13, "{m}");
    }

    #[test]
    fn normal_prob_matches_erf_and_tails() {
        // P(-1 < Z < 1) = erf(1/sqrt 2).
        let p = normal_prob(-1.0, 1.0);
        assert!(rel(p, libm::erf(FRAC_1_SQRT_2)) < 1e-15, "{p}");
        // Far tail, narrow: density times width to first order.
        let (lo, hi) = (30.0, 30.0 + 1e-6);
        let p = normal_prob(lo, hi);
        assert!(rel(p, npdf(0.5 * (lo + hi)) * (hi - lo)) < 1e-9, "{p}");
        // Far tail, wide: the erfc difference.
        let p = normal_prob(20.0, 40.0);
        assert!(rel(p, upper_tail(20.0)) < 1e-15, "{p}");
    }

    #[test]
    fn isotropic_zero_miss_is_rice() {
        // Pc = 1 - exp(-R^2 / (2 sigma^2)) exactly (a Rayleigh radius).
        for (sigma, radius) in [(100.0, 20.0), (5.0, 20.0), (1e4, 1.0), (1.0, 7.0)] {
            let c = scaled(I3, sigma * sigma);
            let out = pc_2d(
                [7e6, 0.0, 0.0],
                [0.0, 7.5e3, 0.0],
                &c,
                [7e6, 0.0, 0.0],
                [0.0, 0.0, 7.5e3],
                &scaled(I3, 0.0),
                radius,
                HardBodyShape::Circle,
                NpdPolicy::Raise,
            )
            .unwrap();
            let exact = -(-radius * radius / (2.0 * sigma * sigma)).exp_m1();
            assert!(
                rel(out.pc, exact) < 1e-9,
                "{sigma} {radius}: {} vs {exact}",
                out.pc
            );
            assert_eq!(out.encounter.miss_distance, 0.0);
            assert!(!out.repaired);
        }
    }

    #[test]
    fn anisotropic_circle_matches_polar_quadrature() {
        let cases = [
            ([5.05, 0.0], [[115.04, -797.69], [-797.69, 5651.79]], 15.0),
            ([120.0, -30.0], [[900.0, 250.0], [250.0, 400.0]], 10.0),
            ([0.0, 0.0], [[4.0, 1.0], [1.0, 9.0]], 3.0),
            ([2.0, 1.0], [[0.5, 0.2], [0.2, 0.3]], 2.5),
        ];
        for (miss, c, radius) in cases {
            let (pc, _, _) =
                encounter_plane_pc(miss, &c, radius, HardBodyShape::Circle, NpdPolicy::Raise)
                    .unwrap();
            let reference = polar_reference(miss, c, radius);
            assert!(rel(pc, reference) < 1e-8, "{miss:?}: {pc} vs {reference}");
        }
    }

    #[test]
    fn square_matches_erf_product_and_2d_rule() {
        // Uncorrelated: product of erf differences.
        let (sx, sz, half) = (30.0_f64, 12.0_f64, 8.0);
        let miss = [25.0, 0.0];
        let (pc, _, _) = encounter_plane_pc(
            miss,
            &[[sx * sx, 0.0], [0.0, sz * sz]],
            half,
            HardBodyShape::Square,
            NpdPolicy::Raise,
        )
        .unwrap();
        let fx = 0.5
            * (libm::erf((miss[0] + half) / (sx * 2f64.sqrt()))
                - libm::erf((miss[0] - half) / (sx * 2f64.sqrt())));
        let fz = libm::erf(half / (sz * 2f64.sqrt()));
        assert!(rel(pc, fx * fz) < 1e-13, "{pc} vs {}", fx * fz);
        // Correlated: a tensor Gauss-Legendre rule over the square.
        let c = [[900.0, 250.0], [250.0, 400.0]];
        let (pc, _, _) =
            encounter_plane_pc(miss, &c, half, HardBodyShape::Square, NpdPolicy::Raise).unwrap();
        let det = c[0][0] * c[1][1] - c[0][1] * c[0][1];
        let (x, w) = gauss_legendre(60);
        let mut reference = 0.0;
        for (xi, wi) in x.iter().zip(&w) {
            for (zj, wj) in x.iter().zip(&w) {
                let u = [miss[0] + half * xi, miss[1] + half * zj];
                let q = (c[1][1] * u[0] * u[0] - 2.0 * c[0][1] * u[0] * u[1]
                    + c[0][0] * u[1] * u[1])
                    / det;
                reference += wi * wj * half * half * (-0.5 * q).exp() / (2.0 * PI * det.sqrt());
            }
        }
        assert!(rel(pc, reference) < 1e-10, "{pc} vs {reference}");
        // The equal-area square of a tiny body tends to the circle (same area, same density).
        let small = 0.01;
        let (sq, _, _) = encounter_plane_pc(
            miss,
            &c,
            small,
            HardBodyShape::SquareEqualArea,
            NpdPolicy::Raise,
        )
        .unwrap();
        let (ci, _, _) =
            encounter_plane_pc(miss, &c, small, HardBodyShape::Circle, NpdPolicy::Raise).unwrap();
        assert!(rel(sq, ci) < 1e-6, "{sq} vs {ci}");
    }

    #[test]
    fn tiny_and_thin_covariances() {
        // Both sigmas far below the radius, miss inside: Pc = 1.
        let (pc, _, _) = encounter_plane_pc(
            [3.0, 0.0],
            &[[1e-6, 0.0], [0.0, 4e-6]],
            10.0,
            HardBodyShape::Circle,
            NpdPolicy::Raise,
        )
        .unwrap();
        assert!((pc - 1.0).abs() < 1e-12, "{pc}");
        // A needle (sigma 1e-3 m across, 1 km along) through the disc centre: the fraction
        // of the along-axis normal inside the chord, ~ 2 R / (sqrt(2 pi) 1000).
        let (pc, _, _) = encounter_plane_pc(
            [0.0, 0.0],
            &[[1e-6, 0.0], [0.0, 1e6]],
            5.0,
            HardBodyShape::Circle,
            NpdPolicy::Raise,
        )
        .unwrap();
        let expected = 1.0 - 2.0 * upper_tail(5.0 / 1000.0);
        assert!(rel(pc, expected) < 1e-6, "{pc} vs {expected}");
        // Far miss: vanishingly small but never NaN.
        let (pc, _, _) = encounter_plane_pc(
            [1e4, 0.0],
            &[[1.0, 0.0], [0.0, 1.0]],
            1.0,
            HardBodyShape::Circle,
            NpdPolicy::Raise,
        )
        .unwrap();
        assert_eq!(pc, 0.0);
    }

    #[test]
    fn npd_is_repaired_or_refused() {
        let c = [[1e6, 2e6], [2e6, 1e6]]; // eigenvalues 3e6 and -1e6
        let err = encounter_plane_pc(
            [1.0, 0.0],
            &c,
            20.0,
            HardBodyShape::Circle,
            NpdPolicy::Raise,
        )
        .unwrap_err();
        assert!(err.to_string().contains("not positive definite"), "{err}");
        let (pc, used, repaired) = encounter_plane_pc(
            [1.0, 0.0],
            &c,
            20.0,
            HardBodyShape::Circle,
            NpdPolicy::Repair,
        )
        .unwrap();
        assert!(repaired);
        assert!(pc.is_finite() && (0.0..=1.0).contains(&pc));
        let e = Eigen2::of(&used);
        assert!(
            (e.l2 - (CLIP_FACTORS[0] * 20.0_f64).powi(2)).abs() < 1e-6 * e.l1,
            "{e:?}"
        );
        assert!(rel(e.l1, 3e6) < 1e-12);
        assert!(cholesky_ok(&used));
        // Eigenvalues 18 orders apart: the standard floor cannot be represented next to
        // the large one, a larger CARA factor is used and the result is positive definite.
        let c = [[3.86e12, -1.98e12], [-1.98e12, 1.0146e12]];
        let (pc, used, repaired) = encounter_plane_pc(
            [5e4, 0.0],
            &c,
            20.0,
            HardBodyShape::Circle,
            NpdPolicy::Repair,
        )
        .unwrap();
        assert!(
            repaired && cholesky_ok(&used) && pc < 1e-10,
            "{used:?} {pc}"
        );
    }

    #[test]
    fn encounter_frame_and_bad_input() {
        let r1 = [7e6, 0.0, 0.0];
        let v1 = [0.0, 7.5e3, 0.0];
        // Object 2 100 m above along z, crossing at 10 km/s along x.
        let enc = encounter(r1, v1, &I3, [7e6, 0.0, 100.0], [1e4, 7.5e3, 0.0], &I3).unwrap();
        assert!((enc.miss_distance - 100.0).abs() < 1e-9);
        assert!(enc.miss[1].abs() < 1e-9 && enc.miss[0] > 0.0);
        assert!((enc.relative_speed - 1e4).abs() < 1e-9);
        // r parallel to v: a perpendicular is chosen, miss 0.
        let enc = encounter(r1, v1, &I3, [7e6 + 50.0, 0.0, 0.0], [1e4, 7.5e3, 0.0], &I3).unwrap();
        assert_eq!(enc.miss_distance, 0.0);
        let e = enc.axes;
        assert!((dot(e[0], e[1])).abs() < 1e-15 && (dot(e[1], e[2])).abs() < 1e-15);
        // Errors.
        let same = encounter(r1, v1, &I3, [7e6, 0.0, 5.0], v1, &I3).unwrap_err();
        assert!(same.to_string().contains("relative speed"), "{same}");
        let nan = encounter(r1, v1, &I3, [f64::NAN, 0.0, 5.0], v1, &I3).unwrap_err();
        assert!(nan.to_string().contains("r2[0]"), "{nan}");
        let mut bad = I3;
        bad[1][2] = f64::INFINITY;
        let e = encounter(r1, v1, &bad, [7e6, 0.0, 5.0], [1.0, 0.0, 0.0], &I3).unwrap_err();
        assert!(e.to_string().contains("cov1[1][2]"), "{e}");
        let e = pc_2d(
            r1,
            v1,
            &I3,
            [7e6, 0.0, 5.0],
            [1.0, 0.0, 0.0],
            &I3,
            0.0,
            HardBodyShape::Circle,
            NpdPolicy::Repair,
        )
        .unwrap_err();
        assert!(e.to_string().contains("hard_body_radius"), "{e}");
        assert!(HardBodyShape::from_name("disc").is_err());
        assert_eq!(
            HardBodyShape::from_name("square_equal_area").unwrap(),
            HardBodyShape::SquareEqualArea
        );
    }

    /// Tiny deterministic generator for the Monte Carlo tests (SplitMix64 + Box-Muller).
    struct Gen(u64);
    impl Gen {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }
        fn normal(&mut self) -> f64 {
            let (u, v) = (self.next(), self.next());
            (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
        }
    }

    #[test]
    fn pair_count_agrees_with_pc_2d_and_is_thread_independent() {
        // Linear encounter: object 1 along y, object 2 along x, miss 10 m in z; isotropic
        // position scatter of 8 m per object, velocities exact.
        let (sigma, hbr, n) = (8.0, 6.0, 1500);
        let mut g = Gen(7);
        let mut sample = |r: [f64; 3], v: [f64; 3]| -> Vec<[f64; 6]> {
            (0..n)
                .map(|_| {
                    [
                        r[0] + sigma * g.normal(),
                        r[1] + sigma * g.normal(),
                        r[2] + sigma * g.normal(),
                        v[0],
                        v[1],
                        v[2],
                    ]
                })
                .collect()
        };
        let (r1, v1, r2, v2) = ([0.0; 3], [0.0, 7e3, 0.0], [0.0, 0.0, 10.0], [7e3, 0.0, 0.0]);
        let m1 = sample(r1, v1);
        let m2 = sample(r2, v2);
        let mc = pc_pairs(&m1, &m2, hbr, &Progress::default()).unwrap();
        let exact = pc_2d(
            r1,
            v1,
            &scaled(I3, sigma * sigma),
            r2,
            v2,
            &scaled(I3, sigma * sigma),
            hbr,
            HardBodyShape::Circle,
            NpdPolicy::Raise,
        )
        .unwrap()
        .pc;
        let sd = mc.variance.sqrt();
        assert!(
            (mc.pc - exact).abs() < 4.0 * sd,
            "{} +- {sd} vs {exact}",
            mc.pc
        );
        assert_eq!(mc.pairs, (n * n) as u64);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let again = one.install(|| pc_pairs(&m1, &m2, hbr, &Progress::default()).unwrap());
        assert_eq!(again, mc);
    }

    #[test]
    fn pair_count_errors_and_zero_velocity_pairs() {
        let p = Progress::default();
        let a = [
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 3.0, 1.0, 0.0, 0.0],
        ];
        // Same velocity: the separation never changes; 0 and 3 m against HBR 2 m.
        let out = pc_pairs(
            &a,
            &[
                [0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 10.0, 1.0, 0.0, 0.0],
            ],
            2.0,
            &p,
        )
        .unwrap();
        assert_eq!(out.hits, 2);
        assert!(pc_pairs(&a[..1], &a, 1.0, &p).is_err());
        let mut bad = a;
        bad[1][4] = f64::NAN;
        let e = pc_pairs(&a, &bad, 1.0, &p).unwrap_err();
        assert!(e.to_string().contains("members2[1][4]"), "{e}");
        assert!(pc_pairs(&a, &a, -1.0, &p).is_err());
        p.cancel.store(true, std::sync::atomic::Ordering::Relaxed);
        assert_eq!(pc_pairs(&a, &a, 1.0, &p).unwrap_err(), CoreError::Cancelled);
    }
}
