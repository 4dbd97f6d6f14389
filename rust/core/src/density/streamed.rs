//! A sampled field too long to hold at once (a months-long run through an atlas): tiles
//! come from a [`TileSource`] when the integrator reaches them and go when no one is in
//! them any more, so memory follows the number of tiles in use, not the run's length.
//!
//! Every lookup gives the bits the [`GriddedField`] of all the tiles would give: a time
//! is served by the tile the composed field would take it from (at a boundary, the
//! later one), through a one-tile field on the same time axis.

use super::gridded::{GriddedField, STEP_SNAP};
use super::sigma_factor;
use super::{Atmosphere, FieldTile, LaneMemory};
use crate::error::{finite, CoreError};
use crate::frames::EarthRotation;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

/// Where a streamed field's tiles come from (an atlas: memory, disk or sampled now).
pub trait TileSource: Send + Sync {
    /// Tile `k` (0-based, in time order).
    fn tile(&self, k: usize) -> Result<Arc<FieldTile>, CoreError>;
}

/// A field of consecutive tiles loaded on demand: at most `keep` tiles are held by the
/// field (the most recently entered), plus the one each running batch is in.
pub struct StreamedField {
    /// Epoch of the time axis, seconds since J2000 (UT1).
    epoch: f64,
    /// Tile k spans `bounds[k]..bounds[k + 1]`, s from `epoch`.
    bounds: Vec<f64>,
    source: Arc<dyn TileSource>,
    open_altitude: bool,
    keep: usize,
    /// Factor on every sigma (as [`GriddedField::with_sigma_scale`]), given to each tile.
    sigma_scale: f64,
    /// (tile index, its one-tile field), least recently entered first.
    held: Mutex<Vec<(usize, Arc<GriddedField>)>>,
    loads: AtomicUsize,
}

impl std::fmt::Debug for StreamedField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StreamedField")
            .field("epoch", &self.epoch)
            .field("tiles", &(self.bounds.len() - 1))
            .field("keep", &self.keep)
            .finish()
    }
}

impl StreamedField {
    /// A field of `bounds.len() - 1` tiles, tile k over `bounds[k]..bounds[k + 1]` s from
    /// `epoch` (strictly increasing), served by `source`; `keep` (>= 1) tiles held
    /// between lookups. `open_altitude` as [`GriddedField::from_tiles`].
    pub fn new(
        epoch: f64,
        bounds: Vec<f64>,
        source: Box<dyn TileSource>,
        open_altitude: bool,
        keep: usize,
    ) -> Result<Self, CoreError> {
        finite("field epoch", epoch)?;
        if bounds.len() < 2 {
            return Err(CoreError::invalid(
                "tile bounds",
                bounds.len() as f64,
                "need at least two (one tile's start and end)",
            ));
        }
        for (k, &b) in bounds.iter().enumerate() {
            finite(&format!("tile bounds[{k}]"), b)?;
            if k > 0 && b <= bounds[k - 1] {
                return Err(CoreError::invalid(
                    format!("tile bounds[{k}]"),
                    b,
                    format!("must be after bounds[{}] ({} s)", k - 1, bounds[k - 1]),
                ));
            }
        }
        if keep == 0 {
            return Err(CoreError::invalid(
                "keep",
                0.0,
                "must hold at least one tile",
            ));
        }
        Ok(Self {
            epoch,
            bounds,
            source: Arc::from(source),
            open_altitude,
            keep,
            sigma_scale: 1.0,
            held: Mutex::new(Vec::new()),
            loads: AtomicUsize::new(0),
        })
    }

    /// This field with every sigma times `factor` (finite, >= 0): the same source, its
    /// own held tiles.
    pub fn with_sigma_scale(&self, factor: f64) -> Result<Self, CoreError> {
        let factor = sigma_factor(factor)?;
        Ok(Self {
            epoch: self.epoch,
            bounds: self.bounds.clone(),
            source: self.source.clone(),
            open_altitude: self.open_altitude,
            keep: self.keep,
            sigma_scale: self.sigma_scale * factor,
            held: Mutex::new(Vec::new()),
            loads: AtomicUsize::new(0),
        })
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        self.bounds.len() - 1
    }

    /// Whether the field has no tile (never: `new` needs one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Tiles asked of the source so far.
    pub fn loads(&self) -> usize {
        self.loads.load(Ordering::Relaxed)
    }

    /// Bytes of the tiles the field holds now.
    pub fn held_bytes(&self) -> usize {
        self.lock()
            .iter()
            .map(|(_, f)| f.tiles().iter().map(|t| t.bytes()).sum::<usize>())
            .sum()
    }

    fn lock(&self) -> MutexGuard<'_, Vec<(usize, Arc<GriddedField>)>> {
        // A panic elsewhere cannot leave the list half-changed: every change is one call.
        self.held.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The tile that serves `t` s from the epoch, and `t` moved onto its span (only a
    /// time the composed field accepts just outside its span moves; the lookup is the
    /// same there).
    fn locate(&self, t: f64) -> Result<(usize, f64), CoreError> {
        let n = self.len();
        let (lo, hi) = (self.bounds[0], self.bounds[n]);
        let slack = 1e-9 * (hi - lo);
        if !(t >= lo - slack && t <= hi + slack) {
            return Err(CoreError::OutsideField {
                axis: "time (s from field epoch)",
                value: t,
                min: lo,
                max: hi,
                t,
            });
        }
        // As the composed field: a time within STEP_SNAP below a boundary is on it, and a
        // boundary belongs to the later tile.
        let k = self.bounds[..n]
            .partition_point(|&x| x <= t + STEP_SNAP)
            .clamp(1, n)
            - 1;
        Ok((k, t.clamp(self.bounds[k], self.bounds[k + 1])))
    }

    /// The one-tile field of tile `k`, from those held or from the source.
    fn field(&self, k: usize) -> Result<Arc<GriddedField>, CoreError> {
        {
            let mut held = self.lock();
            if let Some(i) = held.iter().position(|(j, _)| *j == k) {
                let entry = held.remove(i);
                let field = entry.1.clone();
                held.push(entry);
                return Ok(field);
            }
        }
        // Loaded without the lock: a slow source (a day sampled now) does not stop the
        // batches that are in held tiles.
        self.loads.fetch_add(1, Ordering::Relaxed);
        let tile = self.source.tile(k)?;
        let (start, end) = tile.span();
        if start != self.bounds[k] || end != self.bounds[k + 1] {
            return Err(CoreError::rejected(
                format!("density tile {k}"),
                format!(
                    "spans {start} to {end} s but the field expects {} to {} s",
                    self.bounds[k],
                    self.bounds[k + 1]
                ),
            ));
        }
        let field = GriddedField::from_tiles(self.epoch, vec![tile], self.open_altitude)?;
        let field = Arc::new(if self.sigma_scale == 1.0 {
            field
        } else {
            field.with_sigma_scale(self.sigma_scale)?
        });
        let mut held = self.lock();
        if let Some((_, other)) = held.first() {
            if !other.tiles()[0].same_grid(&field.tiles()[0]) {
                return Err(CoreError::rejected(
                    format!("density tile {k}"),
                    "has another altitude, latitude or longitude grid than the others",
                ));
            }
        }
        if let Some(i) = held.iter().position(|(j, _)| *j == k) {
            return Ok(held[i].1.clone()); // another batch loaded it meanwhile
        }
        held.push((k, field.clone()));
        if held.len() > self.keep {
            held.remove(0);
        }
        Ok(field)
    }
}

impl Atmosphere for StreamedField {
    fn mean_sigma(
        &self,
        ut1: f64,
        r: [f64; 3],
        rot: &EarthRotation,
    ) -> Result<(f64, f64), CoreError> {
        let t = ut1 - self.epoch;
        let (k, tk) = self.locate(t)?;
        let ut1 = if tk == t { ut1 } else { self.epoch + tk };
        self.field(k)?.mean_sigma(ut1, r, rot)
    }

    /// The batch keeps the one-tile field it is in (in `memory`), so that a lookup in
    /// the same tile takes no lock; entering another tile drops the cell it held.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn mean_sigma_lanes<const W: usize>(
        &self,
        ut1: f64,
        x: &[f64; W],
        y: &[f64; W],
        z: &[f64; W],
        active: &[f64; W],
        rot: &EarthRotation,
        mean: &mut [f64; W],
        sigma: &mut [f64; W],
        memory: &mut LaneMemory<W>,
    ) -> Result<(), CoreError> {
        let t = ut1 - self.epoch;
        let (k, tk) = self.locate(t)?;
        let ut1 = if tk == t { ut1 } else { self.epoch + tk };
        let field = match memory.tile.take() {
            Some((j, f)) if j == k => f,
            _ => {
                memory.cell = [f64::NAN; W];
                memory.time_cell = 0;
                self.field(k)?
            }
        };
        let out = field.mean_sigma_lanes(ut1, x, y, z, active, rot, mean, sigma, memory);
        memory.tile = Some((k, field));
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::PAPER_STATE;
    use crate::dynamics::Perturbation;
    use crate::integrators::FixedMethod;
    use crate::kappa::KappaProcess;
    use crate::montecarlo::{monte_carlo_in, MonteCarloConfig};
    use crate::problem::Problem;
    use crate::progress::Progress;
    use crate::simd::SimdPath;

    const EPOCH: f64 = 8.4e7;
    const HOUR: f64 = 3600.0;

    /// An hour-long tile `k` of a smooth field (100-1,000 km, the whole globe) with a
    /// step at its start: values differ from tile to tile, so that a lookup in the wrong
    /// tile shows.
    fn tile(k: usize) -> FieldTile {
        let t0 = k as f64 * HOUR;
        let nodes = vec![t0, t0 + 1200.0, t0 + 2400.0, t0 + HOUR];
        let (na, nl, no) = (19, 7, 8);
        let (mut ln_mean, mut rel) = (Vec::new(), Vec::new());
        for &t in &nodes {
            for ia in 0..na {
                for il in 0..nl {
                    for io in 0..no {
                        let h = 100e3 + ia as f64 * 50e3;
                        let bump = 0.2 * ((t / 5000.0).sin() + 0.1 * k as f64);
                        ln_mean.push(
                            -12.0 - (h - 100e3) / 55e3 + bump + 0.02 * il as f64 + 0.01 * io as f64,
                        );
                        rel.push(0.1 + 0.02 * k as f64 + 1e-8 * h);
                    }
                }
            }
        }
        FieldTile::new(
            nodes,
            (100e3, 50e3, na),
            (-90.0, 30.0, nl),
            0.0,
            no,
            ln_mean,
            rel,
        )
        .unwrap()
    }

    struct Counting(AtomicUsize);

    impl TileSource for Counting {
        fn tile(&self, k: usize) -> Result<Arc<FieldTile>, CoreError> {
            self.0.fetch_add(1, Ordering::Relaxed);
            if k == 99 {
                return Err(CoreError::rejected("tile 99", "not there"));
            }
            Ok(Arc::new(tile(k)))
        }
    }

    fn config(hours: f64) -> MonteCarloConfig {
        MonteCarloConfig {
            problem: Problem {
                epoch: EPOCH,
                y0: PAPER_STATE,
                // The test field is 10^4 times denser than the air at 400 km: at 0.01
                // m^2/kg the members came down within the first hour and only tiles 0 and
                // 1 were ever flown through (the load count then hung on reloads, and
                // came out 4 under a busy machine). At 1e-6 they fly all five hours,
                // their positions moved hundreds of metres by the density.
                drag: 1e-6,
                floor_altitude: 120e3,
                zonal_degree: 2,
                forces: crate::problem::Forces::AUTO,
            },
            initial_factor: None,
            kappa: KappaProcess::GaussMarkov {
                half_life: 1800.0,
                interval: 300.0,
            },
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 60.0,
            output_times: (0..=(hours as usize)).map(|h| h as f64 * HOUR).collect(),
            members: 24,
            seed: 7,
            record_density: true,
            drag_sigma: 0.1,
        }
    }

    #[test]
    fn a_streamed_field_gives_the_bits_of_the_composed_one() {
        // 5 one-hour tiles, 24 members in 3 batches of 8, each batch crossing every
        // boundary; the streamed field holds one tile (a batch entering a tile another
        // has left loads it again): the same bits as the field of all tiles.
        let n = 5;
        let tiles = (0..n).map(|k| Arc::new(tile(k))).collect();
        let composed = GriddedField::from_tiles(EPOCH, tiles, true).unwrap();
        let bounds = (0..=n).map(|k| k as f64 * HOUR).collect();
        let source = Box::new(Counting(AtomicUsize::new(0)));
        let streamed = StreamedField::new(EPOCH, bounds, source, true, 1).unwrap();
        let cfg = config(n as f64);
        let p = Progress::default();
        let a = monte_carlo_in(SimdPath::Portable, 8, &composed, &cfg, &p).unwrap();
        let b = monte_carlo_in(SimdPath::Portable, 8, &streamed, &cfg, &p).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.positions), bits(&b.positions));
        assert_eq!(bits(&a.velocities), bits(&b.velocities));
        assert_eq!(
            bits(a.densities.as_ref().unwrap()),
            bits(b.densities.as_ref().unwrap())
        );
        // Every member flew to the end, through every tile.
        assert!(b.decay_times.iter().all(|t| t.is_infinite()));
        assert!(streamed.loads() >= n, "{} loads", streamed.loads());
        assert!(streamed.lock().len() <= 1);
        // Scalar lookups at the boundaries and the ends, against the composed field.
        let rot = EarthRotation::new(0.3);
        let r = [6.778e6, 1.0e5, 2.0e5];
        for t in [
            0.0,
            HOUR - 1e-7,
            HOUR,
            2.0 * HOUR + 0.5,
            5.0 * HOUR,
            5.0 * HOUR + 1e-6,
        ] {
            let (m1, s1) = composed.mean_sigma(EPOCH + t, r, &rot).unwrap();
            let (m2, s2) = streamed.mean_sigma(EPOCH + t, r, &rot).unwrap();
            assert_eq!(
                (m1.to_bits(), s1.to_bits()),
                (m2.to_bits(), s2.to_bits()),
                "t = {t}"
            );
        }
    }

    #[test]
    fn a_scaled_streamed_field_is_the_scaled_composed_one() {
        // The scaled copy shares the source, holds its own tiles and gives the bits of the
        // composed field scaled alike; the original is unchanged.
        let n = 3;
        let tiles = (0..n).map(|k| Arc::new(tile(k))).collect();
        let composed = GriddedField::from_tiles(EPOCH, tiles, true)
            .unwrap()
            .with_sigma_scale(0.8)
            .unwrap();
        let bounds = (0..=n).map(|k| k as f64 * HOUR).collect();
        let source = Box::new(Counting(AtomicUsize::new(0)));
        let streamed = StreamedField::new(EPOCH, bounds, source, true, 2).unwrap();
        let scaled = streamed.with_sigma_scale(0.8).unwrap();
        let rot = EarthRotation::new(0.3);
        let r = [6.778e6, 1.0e5, 2.0e5];
        for t in [0.0, 0.5 * HOUR, HOUR, 2.5 * HOUR] {
            let (m1, s1) = composed.mean_sigma(EPOCH + t, r, &rot).unwrap();
            let (m2, s2) = scaled.mean_sigma(EPOCH + t, r, &rot).unwrap();
            let (m3, s3) = streamed.mean_sigma(EPOCH + t, r, &rot).unwrap();
            assert_eq!((m1.to_bits(), s1.to_bits()), (m2.to_bits(), s2.to_bits()));
            assert_eq!(m3.to_bits(), m1.to_bits());
            assert!((s2 / s3 - 0.8).abs() < 1e-15, "t = {t}");
        }
        assert!(streamed.with_sigma_scale(-0.1).is_err());
    }

    #[test]
    fn outside_the_tiles_and_a_failing_source_are_errors() {
        let bounds = (0..=3).map(|k| k as f64 * HOUR).collect();
        let f = StreamedField::new(
            EPOCH,
            bounds,
            Box::new(Counting(AtomicUsize::new(0))),
            true,
            2,
        )
        .unwrap();
        let rot = EarthRotation::new(0.0);
        let r = [6.778e6, 0.0, 0.0];
        match f.mean_sigma(EPOCH + 3.0 * HOUR + 10.0, r, &rot) {
            Err(CoreError::OutsideField { axis, max, .. }) => {
                assert!(axis.starts_with("time"));
                assert_eq!(max, 3.0 * HOUR);
            }
            other => panic!("{other:?}"),
        }
        assert!(f.mean_sigma(EPOCH - 10.0, r, &rot).is_err());
        // A tile whose span is not the one the field expects.
        let shifted = vec![0.0, HOUR, 2.5 * HOUR];
        let g = StreamedField::new(
            EPOCH,
            shifted,
            Box::new(Counting(AtomicUsize::new(0))),
            true,
            2,
        )
        .unwrap();
        let e = g.mean_sigma(EPOCH + 2.0 * HOUR, r, &rot).unwrap_err();
        assert!(e.to_string().contains("density tile 1"), "{e}");
        // The source's own error comes through.
        let bounds: Vec<f64> = (0..=100).map(|k| k as f64).collect();
        let h = StreamedField::new(
            EPOCH,
            bounds,
            Box::new(Counting(AtomicUsize::new(0))),
            true,
            2,
        )
        .unwrap();
        let e = h.mean_sigma(EPOCH + 99.5, r, &rot).unwrap_err();
        assert!(e.to_string().contains("not there"), "{e}");
        // Bad bounds and keep.
        let src = || Box::new(Counting(AtomicUsize::new(0)));
        assert!(StreamedField::new(EPOCH, vec![0.0], src(), true, 1).is_err());
        assert!(StreamedField::new(EPOCH, vec![0.0, 0.0], src(), true, 1).is_err());
        assert!(StreamedField::new(EPOCH, vec![0.0, f64::NAN], src(), true, 1).is_err());
        assert!(StreamedField::new(EPOCH, vec![0.0, 1.0], src(), true, 0).is_err());
    }
}
