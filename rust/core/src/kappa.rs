//! The normalised density offset kappa(t) of each member (docs/conventions.md, "The kappa processes"), as node
//! values on a time grid that the integrator steps through exactly.

use crate::error::{positive, CoreError};
use crate::rng::MemberStream;

/// A kappa process.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KappaProcess {
    /// i.i.d. N(0,1) held over each `step` s (the paper's "traditional" Monte Carlo).
    White { step: f64 },
    /// i.i.d. N(0,1) nodes every `interval` s, linear in between (paper's method 1).
    Interpolated { interval: f64 },
    /// First-order Gauss-Markov with the given half-life (s), exact discretisation on
    /// nodes every `interval` s, linear between them (paper's method 2). The nodes are the
    /// process's own, not the integrator's: a member's path depends on its seed and time
    /// only, whatever the integrator and step.
    GaussMarkov { half_life: f64, interval: f64 },
    /// One N(0,1) draw per member held for the whole run.
    Constant,
    /// N(0,1) held over each `interval`, AR(1) with `correlation` across intervals (the
    /// process the CCSP filter is equivalent to).
    PiecewiseConstant { interval: f64, correlation: f64 },
    /// Sum of two independent unit Gauss-Markov terms, sqrt(1 - w) f + sqrt(w) s, f with
    /// `half_life` and s with `slow_half_life` (s), w = `slow_fraction` in [0, 1], on nodes
    /// every `interval` s, linear between them: the process calibrated on observed
    /// densities, whose errors decorrelate within hours in part and persist for days in
    /// part (docs/density-calibration.md).
    TwoScale {
        half_life: f64,
        slow_half_life: f64,
        slow_fraction: f64,
        interval: f64,
    },
}

/// A node of a kappa path: `fast` is kappa itself for every process but
/// [`KappaProcess::TwoScale`], whose two hidden terms are `fast` and `slow`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KappaNode {
    pub fast: f64,
    pub slow: f64,
}

impl KappaProcess {
    /// Names of the kinds for [`KappaProcess::from_spec`], as the Python API and scenario
    /// files spell them.
    pub const KINDS: [&'static str; 6] = [
        "white",
        "interpolated",
        "gauss_markov",
        "constant",
        "piecewise_constant",
        "two_scale",
    ];

    /// The process named `kind` (one of [`KappaProcess::KINDS`]) with its parameters in
    /// field order (step, interval or half-life first, s; then the correlation of
    /// "piecewise_constant" or the node interval of "gauss_markov"; "two_scale" takes
    /// half_life, slow_half_life, slow_fraction, interval). Missing ones read as 0 and
    /// are refused by [`KappaProcess::check`].
    pub fn from_spec(kind: &str, params: &[f64]) -> Result<Self, CoreError> {
        let p = |i: usize| params.get(i).copied().unwrap_or(0.0);
        let (a, b) = (p(0), p(1));
        Ok(match kind {
            "white" => Self::White { step: a },
            "interpolated" => Self::Interpolated { interval: a },
            "gauss_markov" => Self::GaussMarkov {
                half_life: a,
                interval: b,
            },
            "constant" => Self::Constant,
            "piecewise_constant" => Self::PiecewiseConstant {
                interval: a,
                correlation: b,
            },
            "two_scale" => Self::TwoScale {
                half_life: a,
                slow_half_life: b,
                slow_fraction: p(2),
                interval: p(3),
            },
            other => {
                return Err(CoreError::UnknownName {
                    what: "kappa process",
                    name: other.to_string(),
                    expected: &Self::KINDS,
                })
            }
        })
    }

    /// Validates the parameters.
    pub fn check(&self) -> Result<(), CoreError> {
        match *self {
            Self::White { step } => positive("White step", step).map(|_| ()),
            Self::Interpolated { interval } => {
                positive("Interpolated interval", interval).map(|_| ())
            }
            Self::GaussMarkov {
                half_life,
                interval,
            } => {
                positive("GaussMarkov half_life", half_life)?;
                positive("GaussMarkov interval", interval).map(|_| ())
            }
            Self::Constant => Ok(()),
            Self::PiecewiseConstant {
                interval,
                correlation,
            } => {
                positive("PiecewiseConstant interval", interval)?;
                if !(correlation.is_finite() && correlation > -1.0 && correlation < 1.0) {
                    return Err(CoreError::invalid(
                        "PiecewiseConstant correlation",
                        correlation,
                        "must lie in (-1, 1)",
                    ));
                }
                Ok(())
            }
            Self::TwoScale {
                half_life,
                slow_half_life,
                slow_fraction,
                interval,
            } => {
                positive("TwoScale half_life", half_life)?;
                positive("TwoScale slow_half_life", slow_half_life)?;
                positive("TwoScale interval", interval)?;
                if !(0.0..=1.0).contains(&slow_fraction) {
                    return Err(CoreError::invalid(
                        "TwoScale slow_fraction",
                        slow_fraction,
                        "must lie in [0, 1]",
                    ));
                }
                Ok(())
            }
        }
    }

    /// Spacing of the kappa nodes, s (independent of the integrator); None for a process
    /// without nodes after t = 0 (Constant).
    pub fn node_spacing(&self) -> Option<f64> {
        match *self {
            Self::White { step } => Some(step),
            Self::Interpolated { interval }
            | Self::PiecewiseConstant { interval, .. }
            | Self::GaussMarkov { interval, .. }
            | Self::TwoScale { interval, .. } => Some(interval),
            Self::Constant => None,
        }
    }

    /// Whether kappa is linear (true) or held constant (false) between nodes.
    pub fn is_linear(&self) -> bool {
        matches!(
            self,
            Self::Interpolated { .. } | Self::GaussMarkov { .. } | Self::TwoScale { .. }
        )
    }

    /// The integration step: the largest step <= `max_step` that divides the node spacing
    /// (so that every node is a step boundary).
    pub fn integration_step(&self, max_step: f64) -> f64 {
        match self.node_spacing() {
            Some(d) => d / (d / max_step * (1.0 - 1e-12)).ceil().max(1.0),
            None => max_step,
        }
    }

    /// First node (one normal draw; two for TwoScale, fast first).
    pub fn first(&self, stream: &mut MemberStream) -> KappaNode {
        let fast = stream.normal();
        let slow = match self {
            Self::TwoScale { .. } => stream.normal(),
            _ => 0.0,
        };
        KappaNode { fast, slow }
    }

    /// Kappa at a node.
    pub fn value(&self, node: &KappaNode) -> f64 {
        match *self {
            Self::TwoScale { slow_fraction, .. } => {
                (1.0 - slow_fraction).sqrt() * node.fast + slow_fraction.sqrt() * node.slow
            }
            _ => node.fast,
        }
    }

    /// Node following `prev` after `dt` s.
    pub fn next(&self, prev: &KappaNode, dt: f64, stream: &mut MemberStream) -> KappaNode {
        let fast = match *self {
            Self::White { .. } | Self::Interpolated { .. } => stream.normal(),
            Self::GaussMarkov { half_life, .. } | Self::TwoScale { half_life, .. } => {
                gauss_markov_step(prev.fast, half_life, dt, stream)
            }
            Self::PiecewiseConstant { correlation, .. } => {
                correlation * prev.fast + (1.0 - correlation * correlation).sqrt() * stream.normal()
            }
            Self::Constant => prev.fast,
        };
        let slow = match *self {
            Self::TwoScale { slow_half_life, .. } => {
                gauss_markov_step(prev.slow, slow_half_life, dt, stream)
            }
            _ => 0.0,
        };
        KappaNode { fast, slow }
    }
}

/// Exact step of a unit Gauss-Markov process over `dt` s.
fn gauss_markov_step(prev: f64, half_life: f64, dt: f64, stream: &mut MemberStream) -> f64 {
    let a = (-std::f64::consts::LN_2 / half_life * dt).exp();
    a * prev + (1.0 - a * a).sqrt() * stream.normal()
}

/// Kappa of `W` lanes on the current node segment [t0, t1]. The lane arrays first, so
/// that they keep the alignment of the struct that holds this one.
#[derive(Debug, Clone, Copy)]
#[repr(C)]
pub struct KappaLanes<const W: usize> {
    pub k0: [f64; W],
    pub k1: [f64; W],
    pub t0: f64,
    pub t1: f64,
    pub linear: bool,
}

impl<const W: usize> KappaLanes<W> {
    /// kappa = 0 everywhere (the mean density).
    pub fn zero() -> Self {
        Self {
            t0: 0.0,
            t1: f64::INFINITY,
            k0: [0.0; W],
            k1: [0.0; W],
            linear: false,
        }
    }

    /// kappa of lane `l` at time `t` in the segment.
    #[inline(always)]
    pub fn at(&self, l: usize, t: f64) -> f64 {
        self.at_weight(l, self.weight(t))
    }

    /// The interpolation weight of time `t` on the segment (0 when kappa is held): the
    /// same for every lane, so the dynamics computes it once per evaluation.
    #[inline(always)]
    pub fn weight(&self, t: f64) -> f64 {
        if self.linear {
            ((t - self.t0) / (self.t1 - self.t0)).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Kappa of lane `l` at interpolation weight `w` (from [`KappaLanes::weight`]).
    #[inline(always)]
    pub fn at_weight(&self, l: usize, w: f64) -> f64 {
        self.k0[l] + (self.k1[l] - self.k0[l]) * w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paths(p: KappaProcess, members: u64, nodes: usize, dt: f64) -> Vec<Vec<f64>> {
        (0..members)
            .map(|m| {
                let mut s = MemberStream::new(11, m);
                let mut k = p.first(&mut s);
                let mut path = vec![p.value(&k)];
                for _ in 1..nodes {
                    k = p.next(&k, dt, &mut s);
                    path.push(p.value(&k));
                }
                path
            })
            .collect()
    }

    #[test]
    fn gauss_markov_is_stationary_with_half_life_correlation() {
        // 4000 members: standard errors 0.016 (mean), 0.022 (variance), 0.014
        // (correlation near 0.5); tolerances are ~4 of them.
        let p = KappaProcess::GaussMarkov {
            half_life: 1080.0,
            interval: 180.0,
        };
        let ps = paths(p, 4000, 61, 180.0);
        for node in [0, 30, 60] {
            let xs: Vec<f64> = ps.iter().map(|p| p[node]).collect();
            let mean = xs.iter().sum::<f64>() / xs.len() as f64;
            let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
            assert!(
                mean.abs() < 0.065 && (var - 1.0).abs() < 0.09,
                "{node}: {mean} {var}"
            );
        }
        // Lag of one half-life = 6 nodes of 180 s.
        let corr = ps.iter().map(|p| p[20] * p[26]).sum::<f64>() / ps.len() as f64;
        assert!((corr - 0.5).abs() < 0.06, "{corr}");
    }

    #[test]
    fn integration_step_divides_node_spacing() {
        let s = KappaProcess::Interpolated { interval: 1080.0 }.integration_step(180.0);
        assert_eq!(s, 180.0);
        let s = KappaProcess::White { step: 10.0 }.integration_step(180.0);
        assert_eq!(s, 10.0);
        let s = KappaProcess::White { step: 600.0 }.integration_step(180.0);
        assert_eq!(s, 150.0);
        assert_eq!(KappaProcess::Constant.integration_step(180.0), 180.0);
        // Gauss-Markov nodes are the process's own: ABM's 80 s becomes 60 s.
        let gm = KappaProcess::GaussMarkov {
            half_life: 1080.0,
            interval: 180.0,
        };
        assert_eq!(gm.integration_step(80.0), 60.0);
        assert_eq!(gm.integration_step(180.0), 180.0);
        assert_eq!(gm.node_spacing(), Some(180.0));
    }

    #[test]
    fn every_kind_name_parses() {
        for kind in KappaProcess::KINDS {
            assert!(
                KappaProcess::from_spec(kind, &[60.0, 0.5, 0.5, 10.0]).is_ok(),
                "{kind}"
            );
        }
        assert_eq!(
            KappaProcess::from_spec("gauss_markov", &[1080.0, 180.0]).unwrap(),
            KappaProcess::GaussMarkov {
                half_life: 1080.0,
                interval: 180.0
            }
        );
        let e = KappaProcess::from_spec("brownian", &[1.0, 0.0]).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("unknown kappa process \"brownian\"; expected one of white,"),
            "{e}"
        );
    }

    #[test]
    fn piecewise_constant_correlation() {
        let p = KappaProcess::PiecewiseConstant {
            interval: 3600.0,
            correlation: 1.0 / 3.0,
        };
        let ps = paths(p, 4000, 3, 3600.0);
        let corr = ps.iter().map(|p| p[1] * p[2]).sum::<f64>() / ps.len() as f64;
        assert!((corr - 1.0 / 3.0).abs() < 0.065, "{corr}");
        assert!(KappaProcess::PiecewiseConstant {
            interval: 1.0,
            correlation: 1.0
        }
        .check()
        .is_err());
        assert!(KappaProcess::White { step: 0.0 }.check().is_err());
    }

    #[test]
    fn two_scale_correlation_is_the_weighted_sum_of_its_terms() {
        // 4000 members: the variance's standard error is 0.022, a correlation's about
        // 0.014; tolerances are about 4 of them. Half-lives 1 h and 10 h, w = 0.4: at a lag
        // of 1 h the correlation is 0.6 * 0.5 + 0.4 * 2^-0.1 = 0.6732, at 10 h
        // 0.6 * 2^-10 + 0.4 * 0.5 = 0.2006.
        let p = KappaProcess::TwoScale {
            half_life: 3600.0,
            slow_half_life: 36000.0,
            slow_fraction: 0.4,
            interval: 600.0,
        };
        p.check().unwrap();
        let ps = paths(p, 4000, 121, 600.0);
        let var = ps.iter().map(|p| p[100] * p[100]).sum::<f64>() / ps.len() as f64;
        assert!((var - 1.0).abs() < 0.09, "{var}");
        let corr = |lag: usize| ps.iter().map(|p| p[20] * p[20 + lag]).sum::<f64>() / 4000.0;
        let one = 0.6 * 0.5 + 0.4 * 2f64.powf(-0.1);
        let ten = 0.6 * 2f64.powi(-10) + 0.4 * 0.5;
        assert!((corr(6) - one).abs() < 0.06, "{}", corr(6));
        assert!((corr(60) - ten).abs() < 0.06, "{}", corr(60));
        let bad = KappaProcess::from_spec("two_scale", &[3600.0, 36000.0, 1.5, 600.0]);
        assert!(bad.unwrap().check().is_err());
    }
}
