//! A density field sampled on a regular 4-D grid (time, geodetic altitude, geodetic
//! latitude, longitude), holding ln(mean density) and sigma/mean. Any density model,
//! however slow, is sampled once into this form and then drives the integrator at the
//! cost of one multilinear interpolation per evaluation.
//!
//! The time axis is a list of nodes; a node given twice marks a discontinuity (the first
//! copy holds the value just before, the second the value from then on), so that density
//! models whose drivers change in steps (3-hourly ap, daily F10.7) are represented exactly
//! instead of being smeared across a cell.
//!
//! Behaviour outside the grid: time, altitude and latitude outside their axis range are
//! an error ([`CoreError::OutsideField`]) naming the axis, the value and the covered
//! range; there is no extrapolation and no clamping. Longitude is periodic and always
//! covered.

use super::exponential::exp;
use super::sigma_factor;
use super::{Atmosphere, LaneMemory};
use crate::error::{finite, CoreError};
use crate::frames::{geodetic, geodetic_lanes, EarthRotation};
use std::f64::consts::TAU;
use std::sync::Arc;

/// A uniform axis: `len` nodes at `start + i * step`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    start: f64,
    step: f64,
    len: usize,
}

impl Axis {
    fn checked(name: &str, start: f64, step: f64, len: usize) -> Result<Self, CoreError> {
        finite(&format!("{name} axis start"), start)?;
        finite(&format!("{name} axis step"), step)?;
        if step <= 0.0 {
            return Err(CoreError::invalid(
                format!("{name} axis step"),
                step,
                "must be > 0",
            ));
        }
        if len < 2 {
            return Err(CoreError::invalid(
                format!("{name} axis length"),
                len as f64,
                "needs at least 2 nodes",
            ));
        }
        Ok(Self { start, step, len })
    }

    /// Last node.
    fn end(&self) -> f64 {
        self.start + self.step * (self.len - 1) as f64
    }

    /// Cell index and fraction of `x`, or `None` outside [start, end]. A rounding slack
    /// of 1e-9 cells is accepted at both ends.
    #[inline(always)]
    fn locate(&self, x: f64) -> Option<(usize, f64)> {
        let u = (x - self.start) / self.step;
        let last = (self.len - 1) as f64;
        if !(u >= -1e-9 && u <= last + 1e-9) {
            return None;
        }
        let i = (u.floor().max(0.0) as usize).min(self.len - 2);
        Some((i, (u - i as f64).clamp(0.0, 1.0)))
    }
}

/// Times this close below a node (s) are taken to be on it.
pub(super) const STEP_SNAP: f64 = 1e-6;

/// A non-decreasing time axis whose repeated nodes mark discontinuities.
#[derive(Debug, Clone, PartialEq)]
struct TimeNodes {
    nodes: Vec<f64>,
}

impl TimeNodes {
    fn checked(nodes: Vec<f64>) -> Result<Self, CoreError> {
        let n = nodes.len();
        if n < 2 {
            return Err(CoreError::invalid(
                "time axis length",
                n as f64,
                "needs at least 2 nodes",
            ));
        }
        for (i, &t) in nodes.iter().enumerate() {
            finite(&format!("time node {i}"), t)?;
            if i > 0 && t < nodes[i - 1] {
                return Err(CoreError::invalid(
                    format!("time node {i}"),
                    t,
                    format!("time nodes must not decrease (previous {})", nodes[i - 1]),
                ));
            }
            if i > 1 && t == nodes[i - 2] {
                return Err(CoreError::invalid(
                    format!("time node {i}"),
                    t,
                    "a node may appear at most twice",
                ));
            }
        }
        if nodes[1] == nodes[0] || nodes[n - 1] == nodes[n - 2] {
            return Err(CoreError::invalid(
                "time axis",
                nodes[0],
                "the first and last cells must not be empty",
            ));
        }
        Ok(Self { nodes })
    }

    /// First node.
    fn start(&self) -> f64 {
        self.nodes[0]
    }

    /// Last node.
    fn end(&self) -> f64 {
        self.nodes[self.nodes.len() - 1]
    }

    /// [`TimeNodes::locate`], trying the cell `hint` first (the cell of the previous
    /// stage, which the next one mostly shares) and updating it.
    #[inline(always)]
    fn locate_near(&self, t: f64, hint: &mut usize) -> Option<(usize, f64)> {
        let i = *hint;
        if i + 1 < self.nodes.len() {
            let (lo, hi) = (self.nodes[i], self.nodes[i + 1]);
            // The same cell as the search would find: lo <= t + snap < hi.
            if lo <= t + STEP_SNAP && t + STEP_SNAP < hi {
                return Some((i, ((t - lo) / (hi - lo)).clamp(0.0, 1.0)));
            }
        }
        let found = self.locate(t);
        if let Some((i, _)) = found {
            *hint = i;
        }
        found
    }

    /// Cell and fraction of `t`; at a repeated node the later cell (value after the jump).
    #[inline(always)]
    fn locate(&self, t: f64) -> Option<(usize, f64)> {
        let n = self.nodes.len();
        let slack = 1e-9 * (self.end() - self.start());
        if !(t >= self.start() - slack && t <= self.end() + slack) {
            return None;
        }
        // First node strictly after t; the cell starts one before it. A time within 1 us
        // below a node counts as on it, so that a time that is a step epoch but arrives
        // with rounding takes the value after the step, as the model's drivers do.
        let j = self
            .nodes
            .partition_point(|&x| x <= t + STEP_SNAP)
            .clamp(1, n - 1);
        let i = j - 1;
        let width = self.nodes[j] - self.nodes[i];
        Some((i, ((t - self.nodes[i]) / width).clamp(0.0, 1.0)))
    }
}

/// One time window of a sampled field (an atlas tile: for example one UTC day): its own
/// time nodes, on the time axis of the fields it goes into, and the values on them. Tiles
/// are shared (`Arc`) between the fields composed from them, so a field over a few days
/// of a long catalog costs no copy of the values.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldTile {
    time: TimeNodes,
    alt: Axis,
    /// Latitude axis in radians.
    lat: Axis,
    /// First longitude node in radians; nodes are `nlon` equal steps around the globe.
    lon0: f64,
    nlon: usize,
    /// (ln mean, rel sigma) per node, row-major [time][alt][lat][lon]: the two values a
    /// lookup reads at a corner share a cache line (and so, mostly, do the longitude
    /// neighbours'), halving the lines touched against two separate tables.
    table: Vec<[f64; 2]>,
}

impl FieldTile {
    /// Builds a tile. `time` nodes in seconds on the field's time axis (non-decreasing, a
    /// repeated node marks a discontinuity); `alt` in metres (geodetic); `lat` in degrees
    /// (geodetic); longitude nodes at `lon0_deg + k * 360 / nlon` degrees, periodic.
    /// `ln_mean` (ln of kg/m^3) and `rel_sigma` (sigma/mean, >= 0) are row-major
    /// [time][alt][lat][lon] (read, not kept: the tile stores them interleaved).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        time: Vec<f64>,
        alt: (f64, f64, usize),
        lat_deg: (f64, f64, usize),
        lon0_deg: f64,
        nlon: usize,
        ln_mean: impl AsRef<[f64]>,
        rel_sigma: impl AsRef<[f64]>,
    ) -> Result<Self, CoreError> {
        let (ln_mean, rel_sigma) = (ln_mean.as_ref(), rel_sigma.as_ref());
        let time = TimeNodes::checked(time)?;
        let alt = Axis::checked("altitude", alt.0, alt.1, alt.2)?;
        let lat = Axis::checked("latitude", lat_deg.0, lat_deg.1, lat_deg.2)?;
        if lat.start < -90.0 - 1e-9 || lat.end() > 90.0 + 1e-9 {
            return Err(CoreError::invalid(
                "latitude axis",
                lat.end(),
                format!(
                    "must lie within [-90, 90] deg, spans {} to {}",
                    lat.start,
                    lat.end()
                ),
            ));
        }
        finite("longitude start", lon0_deg)?;
        if nlon < 3 {
            return Err(CoreError::invalid(
                "longitude axis length",
                nlon as f64,
                "needs at least 3 nodes around the globe",
            ));
        }
        let n = time.nodes.len() * alt.len * lat.len * nlon;
        for (name, v) in [("ln_mean", ln_mean), ("rel_sigma", rel_sigma)] {
            if v.len() != n {
                return Err(CoreError::shape(
                    name,
                    format!(
                        "expected {} values ({} x {} x {} x {}), got {}",
                        n,
                        time.nodes.len(),
                        alt.len,
                        lat.len,
                        nlon,
                        v.len()
                    ),
                ));
            }
        }
        if let Some(i) = ln_mean.iter().position(|x| !x.is_finite()) {
            return Err(CoreError::non_finite(format!("ln_mean[{i}]"), ln_mean[i]));
        }
        if let Some(i) = rel_sigma.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(CoreError::invalid(
                format!("rel_sigma[{i}]"),
                rel_sigma[i],
                "must be finite and >= 0",
            ));
        }
        Ok(Self {
            time,
            alt,
            lat: Axis {
                start: lat.start.to_radians(),
                step: lat.step.to_radians(),
                len: lat.len,
            },
            lon0: lon0_deg.to_radians(),
            nlon,
            table: ln_mean
                .iter()
                .zip(rel_sigma)
                .map(|(&m, &s)| [m, s])
                .collect(),
        })
    }

    /// First and last time node, s.
    pub fn span(&self) -> (f64, f64) {
        (self.time.start(), self.time.end())
    }

    /// Bytes of the values held.
    pub fn bytes(&self) -> usize {
        self.table.len() * std::mem::size_of::<[f64; 2]>()
    }

    /// Whether `other` has the same spatial grid.
    pub(super) fn same_grid(&self, other: &Self) -> bool {
        self.alt == other.alt
            && self.lat == other.lat
            && self.lon0 == other.lon0
            && self.nlon == other.nlon
    }
}

/// Density sampled on a (time, altitude, latitude, longitude) grid: one tile, or tiles
/// that follow each other in time on one spatial grid.
#[derive(Debug, Clone, PartialEq)]
pub struct GriddedField {
    /// Epoch of the time axis, seconds since J2000 (UT1).
    epoch: f64,
    /// Every tile's nodes in order; where one tile ends the next begins at the same node,
    /// so the boundary is a repeated node (a step, if the values differ).
    time: TimeNodes,
    /// Per time cell: its tile and the cell's index within the tile.
    cells: Vec<(u32, u32)>,
    tiles: Vec<Arc<FieldTile>>,
    /// Table index at which each tile's values would start if the tables were one (as a
    /// float, for the lane memory's cell key: unique across tiles).
    offsets: Vec<f64>,
    alt: Axis,
    /// Latitude axis in radians.
    lat: Axis,
    lon0: f64,
    nlon: usize,
    /// Reciprocals of the altitude, latitude and longitude steps and of the longitude
    /// count, for the lane lookup (computed once: four divisions per evaluation showed).
    inv: [f64; 4],
    /// Open in altitude (an atlas field): above the top node ln(mean) continues along the
    /// top cell's slope (an exponential with the local scale height) and sigma/mean keeps
    /// its top value; below the bottom node both keep the bottom level's values (only an
    /// integrator stage of a step that crosses the decay floor goes there: such a step is
    /// cut at the crossing). Without it, either is an error.
    open_altitude: bool,
    /// Factor on every sigma the field gives (1: the tiles' own): a model's uncertainty
    /// widened or narrowed without resampling it (an ensemble's spread-adjusted pool).
    sigma_scale: f64,
}

impl GriddedField {
    /// Builds a field of one tile. `epoch` in seconds since J2000; `time` nodes in seconds
    /// from `epoch`; the other arguments as [`FieldTile::new`]. An error above the grid.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        epoch: f64,
        time: Vec<f64>,
        alt: (f64, f64, usize),
        lat_deg: (f64, f64, usize),
        lon0_deg: f64,
        nlon: usize,
        ln_mean: impl AsRef<[f64]>,
        rel_sigma: impl AsRef<[f64]>,
    ) -> Result<Self, CoreError> {
        let tile = FieldTile::new(time, alt, lat_deg, lon0_deg, nlon, ln_mean, rel_sigma)?;
        Self::from_tiles(epoch, vec![Arc::new(tile)], false)
    }

    /// A field from `tiles` (times in seconds from `epoch`), each starting where the one
    /// before ends, on one spatial grid. With `open_altitude`, altitudes above the top
    /// node are served by the top cell's ln(mean) slope and sigma/mean (see the module
    /// doc) instead of an error.
    pub fn from_tiles(
        epoch: f64,
        tiles: Vec<Arc<FieldTile>>,
        open_altitude: bool,
    ) -> Result<Self, CoreError> {
        finite("field epoch", epoch)?;
        let Some(first) = tiles.first().cloned() else {
            return Err(CoreError::invalid(
                "tiles",
                0.0,
                "a field needs at least one tile",
            ));
        };
        let mut nodes = Vec::new();
        let mut cells = Vec::new();
        let mut offsets = Vec::with_capacity(tiles.len());
        let mut offset = 0usize;
        for (k, tile) in tiles.iter().enumerate() {
            if !tile.same_grid(&first) {
                return Err(CoreError::invalid(
                    format!("tile {k}"),
                    k as f64,
                    "has another altitude, latitude or longitude grid than tile 0",
                ));
            }
            if let Some(&last) = nodes.last() {
                if tile.time.start() != last {
                    return Err(CoreError::invalid(
                        format!("tile {k} start"),
                        tile.time.start(),
                        format!("must equal the end of tile {} ({last} s)", k - 1),
                    ));
                }
                // The zero-width cell at the boundary (never located: a repeated node
                // takes the later cell).
                cells.push((k as u32, 0));
            }
            let n = tile.time.nodes.len();
            nodes.extend_from_slice(&tile.time.nodes);
            cells.extend((0..n - 1).map(|i| (k as u32, i as u32)));
            offsets.push(offset as f64);
            offset += tile.table.len();
        }
        let time = TimeNodes::checked(nodes)?;
        let (alt, lat, nlon) = (first.alt, first.lat, first.nlon);
        Ok(Self {
            epoch,
            time,
            cells,
            offsets,
            alt,
            lat,
            lon0: first.lon0,
            nlon,
            inv: [
                1.0 / alt.step,
                1.0 / lat.step,
                1.0 / (TAU / nlon as f64),
                1.0 / nlon as f64,
            ],
            open_altitude,
            tiles,
            sigma_scale: 1.0,
        })
    }

    /// The tiles, in time order.
    pub fn tiles(&self) -> &[Arc<FieldTile>] {
        &self.tiles
    }

    /// Tile, its values and the cell within it of global time cell `it`.
    #[inline(always)]
    fn cell(&self, it: usize) -> (usize, &[[f64; 2]], usize) {
        let (k, local) = self.cells[it];
        let k = k as usize;
        (k, &self.tiles[k].table, local as usize)
    }

    /// This field with every sigma times `factor` (finite, >= 0; the tiles are shared).
    pub fn with_sigma_scale(&self, factor: f64) -> Result<Self, CoreError> {
        let factor = sigma_factor(factor)?;
        Ok(Self {
            sigma_scale: self.sigma_scale * factor,
            ..self.clone()
        })
    }

    /// Mean and sigma at `ut1` seconds since J2000 and geodetic (lat, lon) in rad, alt m.
    pub fn at_geodetic(
        &self,
        ut1: f64,
        lat: f64,
        lon: f64,
        alt: f64,
    ) -> Result<(f64, f64), CoreError> {
        let t = ut1 - self.epoch;
        if !(lat.is_finite() && lon.is_finite() && alt.is_finite()) {
            // Not a place outside the field: the integrated state itself went bad.
            return Err(CoreError::Rejected {
                name: "the integrated state".into(),
                reason: format!(
                    "its position became non-finite (altitude {alt} m) at t = {t} s from the \
                     field's epoch: the orbit diverged, e.g. under a density or an \
                     acceleration far beyond any real atmosphere"
                ),
            });
        }
        let outside =
            |axis: &'static str, value: f64, a: &Axis, scale: f64| CoreError::OutsideField {
                axis,
                value: value * scale,
                min: a.start * scale,
                max: a.end() * scale,
                t,
            };
        let (it, ft) = self.time.locate(t).ok_or(CoreError::OutsideField {
            axis: "time (s from field epoch)",
            value: t,
            min: self.time.start(),
            max: self.time.end(),
            t,
        })?;
        let above = self.open_altitude && alt > self.alt.end();
        let below = self.open_altitude && alt < self.alt.start;
        let (ia, fa_s, fa_m) = if above {
            let ia = self.alt.len - 2;
            (ia, 1.0, (alt - self.alt.start) / self.alt.step - ia as f64)
        } else if below {
            (0, 0.0, 0.0)
        } else {
            let (ia, fa) = self
                .alt
                .locate(alt)
                .ok_or_else(|| outside("altitude (m)", alt, &self.alt, 1.0))?;
            (ia, fa, fa)
        };
        let (il, fl) = self.lat.locate(lat).ok_or_else(|| {
            outside(
                "latitude (deg)",
                lat,
                &self.lat,
                180.0 / std::f64::consts::PI,
            )
        })?;
        let step_lon = TAU / self.nlon as f64;
        let u = ((lon - self.lon0) / step_lon).rem_euclid(self.nlon as f64);
        let io0 = (u.floor() as usize).min(self.nlon - 1);
        let fo = u - io0 as f64;
        let io1 = if io0 + 1 == self.nlon { 0 } else { io0 + 1 };

        let (_, table, it) = self.cell(it);
        let (na, nl, no) = (self.alt.len, self.lat.len, self.nlon);
        let mut ln_m = 0.0;
        let mut rs = 0.0;
        for (dt, wt) in [(0, 1.0 - ft), (1, ft)] {
            for (da, wm, ws) in [(0, 1.0 - fa_m, 1.0 - fa_s), (1, fa_m, fa_s)] {
                for (dl, wl) in [(0, 1.0 - fl), (1, fl)] {
                    let row = (((it + dt) * na + ia + da) * nl + il + dl) * no;
                    let (a, b) = (row + io0, row + io1);
                    let (ca, cb) = (table[a], table[b]);
                    ln_m += wt * wm * wl * ((1.0 - fo) * ca[0] + fo * cb[0]);
                    rs += wt * ws * wl * ((1.0 - fo) * ca[1] + fo * cb[1]);
                }
            }
        }
        let mean = ln_m.exp();
        Ok((mean, rs * mean * self.sigma_scale))
    }
}

impl Atmosphere for GriddedField {
    fn mean_sigma(
        &self,
        ut1: f64,
        r: [f64; 3],
        rot: &EarthRotation,
    ) -> Result<(f64, f64), CoreError> {
        let g = geodetic(rot.to_fixed(r));
        self.at_geodetic(ut1, g.lat, g.lon, g.alt)
    }

    /// The batch lookup of the integrators: the time cell once for all lanes, then per
    /// lane the branch-free geodetic conversion ([`geodetic_lanes`]), the cell and the
    /// fractions in straight-line lane loops that vectorise, the cell's 16 corners (kept in
    /// `memory` while the lane stays in the cell), nested linear interpolation and the lane
    /// `exp`. Every batch width gives a lane the same bits; agrees with the scalar
    /// [`Atmosphere::mean_sigma`] (exact geodetic conversion) to the lane conversion's
    /// 7 cm and 3e-7 rad, a few 1e-6 of the density. A lane the lane conversion puts
    /// outside the grid goes through the scalar lookup: its error names the axis, and a
    /// value it finds (a position within those centimetres of the edge) is the lane's.
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
        let Some((it, ft)) = self
            .time
            .locate_near(ut1 - self.epoch, &mut memory.time_cell)
        else {
            // Outside the time axis: the scalar lookup of an active lane says so.
            for l in 0..W {
                if active[l] != 0.0 {
                    (mean[l], sigma[l]) = self.mean_sigma(ut1, [x[l], y[l], z[l]], rot)?;
                }
            }
            return Ok(());
        };
        let (tile, table, local) = self.cell(it);
        let (na, nl, no) = (self.alt.len, self.lat.len, self.nlon);
        let (last_a, last_l, nof) = ((na - 1) as f64, (nl - 1) as f64, no as f64);
        // The altitude cell indices outside which a lane is outside (infinite: open).
        let (bottom_a, top_a) = if self.open_altitude {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (-1e-9, last_a + 1e-9)
        };
        let [inv_alt, inv_lat, inv_lon, inv_nlon] = self.inv;
        // Straight-line lane loops (no clamp asserts, no integer work) so that they
        // vectorise: the geodetic position, then the cell and fractions.
        // Latitude and altitude do not change under the rotation about z, so they come
        // from the inertial position, and the longitude is its right ascension minus the
        // rotation angle: the Earth rotation's sine and cosine stay off the critical path.
        let (mut lat, mut ra, mut alt) = ([0.0; W], [0.0; W], [0.0; W]);
        geodetic_lanes(x, y, z, &mut lat, &mut ra, &mut alt);
        let lon_origin = rot.angle + self.lon0;
        // Per lane: the cell's first table index and the longitude neighbour's offset (as
        // floats until the end), the fractions along altitude, latitude and longitude.
        let (mut base_f, mut next_f) = ([0.0; W], [0.0; W]);
        // fa: the altitude fraction of sigma/mean (held above the top), fm: of ln(mean)
        // (beyond 1 above the top: the top cell's slope continued). Equal inside.
        let (mut fa, mut fm, mut fl, mut fo) = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
        let mut outside = [false; W];
        // The cell key of the lane memory is unique across tiles: the tile's offset plus
        // the index within its table.
        let (it_f, offset) = (local as f64, self.offsets[tile]);
        for l in 0..W {
            let ua = (alt[l] - self.alt.start) * inv_alt;
            let ul = (lat[l] - self.lat.start) * inv_lat;
            // `&`, not `&&`: no branches in a lane loop.
            outside[l] =
                !((ua >= bottom_a) & (ua <= top_a) & (ul >= -1e-9) & (ul <= last_l + 1e-9));
            let ia = ua.floor().max(0.0).min(last_a - 1.0);
            let il = ul.floor().max(0.0).min(last_l - 1.0);
            fa[l] = (ua - ia).clamp(0.0, 1.0);
            fm[l] = if ua > last_a { ua - ia } else { fa[l] };
            fl[l] = (ul - il).clamp(0.0, 1.0);
            let uo = (ra[l] - lon_origin) * inv_lon;
            let uo = uo - (uo * inv_nlon).floor() * nof;
            let io = uo.floor().max(0.0).min(nof - 1.0);
            fo[l] = uo - io;
            // Offset of the next longitude node: +1, or back to node 0 past the last.
            next_f[l] = if io + 1.0 == nof { 1.0 - nof } else { 1.0 };
            base_f[l] = offset + ((it_f * na as f64 + ia) * nl as f64 + il) * nof + io;
        }
        // Strides of the time, altitude and latitude neighbours in the table.
        let (st, sa, sl) = (na * nl * no, nl * no, no);
        // Each lane's cell corners, per time node and value: read from the table only when
        // the lane has left the cell it had at the previous stage (mostly it has not). The
        // lanes of a batch are mostly one object's members or sigma points, so they mostly
        // enter a new cell together: its 16 table reads are done once, and when no other
        // lane holds another cell, written to all lanes by vector stores, not lane by lane
        // (32 scattered stores each: the largest cost of a refill).
        let mut pending = [false; W];
        for l in 0..W {
            pending[l] = !outside[l] & (memory.cell[l] != base_f[l]);
        }
        let corners = &mut memory.corners;
        while let Some(first) = pending.iter().position(|&p| p) {
            let key = base_f[first];
            // Exact: table sizes are far below 2^53. The longitude neighbour's offset
            // follows from the cell, so it is the same for every lane entering it.
            let (base, next) = ((key - offset) as usize, next_f[first] as isize);
            let mut values = [0.0; 32];
            for dt in 0..2 {
                for k in 0..4 {
                    // k = 2 * altitude bit + latitude bit; the longitude pair side by side.
                    let a = base + dt * st + (k >> 1) * sa + (k & 1) * sl;
                    let (ca, cb) = (table[a], table[a.wrapping_add_signed(next)]);
                    // The corner and the step to its longitude neighbour: the subtraction
                    // of the longitude interpolation, done once per cell, not per stage
                    // (the same difference, so the same bits).
                    for q in 0..2 {
                        values[(2 * dt + q) * 8 + 2 * k] = ca[q];
                        values[(2 * dt + q) * 8 + 2 * k + 1] = cb[q] - ca[q];
                    }
                }
            }
            // The lanes entering it; `every` stays true if all the others hold it already
            // or are outside (their corners unused: they may take it too).
            let (mut enter, mut every) = ([false; W], true);
            for l in 0..W {
                // `first` always enters: a NaN key would otherwise never leave `pending`.
                let e = pending[l] & ((base_f[l] == key) | (l == first));
                pending[l] &= !e;
                enter[l] = e;
                every &= e | outside[l] | (memory.cell[l] == key);
            }
            if every {
                // Mostly: plain vector stores.
                memory.cell = [key; W];
                for (row, &v) in corners.iter_mut().zip(&values) {
                    *row = [v; W];
                }
            } else {
                // Lane by lane (a blend of each row was vectorised across rows, not lanes:
                // gathers and scatters).
                for l in (0..W).filter(|&l| enter[l]) {
                    memory.cell[l] = key;
                    for (row, &v) in corners.iter_mut().zip(&values) {
                        row[l] = v;
                    }
                }
            }
        }
        // Interpolate in a lane loop that vectorises, per value and time node: along
        // longitude, latitude, altitude (nested linear steps), then along time.
        let (mut ln_m, mut rs) = ([0.0; W], [0.0; W]);
        for l in 0..W {
            let (b, o) = (fl[l], fo[l]);
            let mut v = [0.0; 4];
            for (q, vq) in v.iter_mut().enumerate() {
                let c = |k: usize| corners[q * 8 + k][l];
                let lerp = |x: f64, y: f64, f: f64| f.mul_add(y - x, x);
                let e = [
                    o.mul_add(c(1), c(0)),
                    o.mul_add(c(3), c(2)),
                    o.mul_add(c(5), c(4)),
                    o.mul_add(c(7), c(6)),
                ];
                // Even q: ln(mean), odd: sigma/mean.
                let a = if q % 2 == 0 { fm[l] } else { fa[l] };
                *vq = lerp(lerp(e[0], e[1], b), lerp(e[2], e[3], b), a);
            }
            // q = 2 dt + value: v[0], v[1] at the first time node, v[2], v[3] at the next.
            ln_m[l] = ft.mul_add(v[2] - v[0], v[0]);
            rs[l] = ft.mul_add(v[3] - v[1], v[1]);
        }
        // Mean and sigma, zero outside the grid. The lane exp runs for every lane and an
        // AND with a bit mask zeroes the outside ones: a branch here left the exp scalar
        // (a fifth of a field Monte Carlo on the AVX2 path).
        for l in 0..W {
            let keep = if outside[l] { 0 } else { u64::MAX };
            mean[l] = f64::from_bits(exp(ln_m[l]).to_bits() & keep);
            sigma[l] = f64::from_bits((rs[l] * mean[l] * self.sigma_scale).to_bits() & keep);
        }
        // The scalar lookup of an active lane outside: the error naming the axis and value,
        // or (within the lane conversion's centimetres of an edge) the lane's value.
        for l in 0..W {
            if outside[l] && active[l] != 0.0 {
                (mean[l], sigma[l]) = self.mean_sigma(ut1, [x[l], y[l], z[l]], rot)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lane against scalar lookup, relative: the lane conversion's 7 cm and 3e-7 rad (see
    /// `geodetic_lanes`) times the test field's slopes (1 per 60 km, 0.01 per degree).
    const LANE_TOL: f64 = 3e-6;

    /// A field whose ln(mean) and rel_sigma are affine in every axis, so multilinear
    /// interpolation must reproduce them exactly.
    fn affine_field() -> GriddedField {
        let (nt, na, nl, no) = (3, 4, 5, 8);
        let mut ln_mean = Vec::new();
        let mut rel = Vec::new();
        for it in 0..nt {
            for ia in 0..na {
                for il in 0..nl {
                    for io in 0..no {
                        let t = it as f64 * 600.0;
                        let h = 300e3 + ia as f64 * 50e3;
                        let lat = -60.0 + il as f64 * 30.0;
                        ln_mean.push(-20.0 - h / 60e3 + 1e-4 * t + 0.01 * lat + 0.001 * io as f64);
                        rel.push(0.1 + 1e-6 * t + 1e-7 * h);
                    }
                }
            }
        }
        GriddedField::new(
            100.0,
            vec![0.0, 600.0, 1200.0],
            (300e3, 50e3, na),
            (-60.0, 30.0, nl),
            0.0,
            no,
            ln_mean,
            rel,
        )
        .unwrap()
    }

    #[test]
    fn interpolation_is_exact_for_affine_data() {
        let f = affine_field();
        let (t, h, lat) = (777.0, 412.5e3, 17.25f64);
        let lon = (45.0f64 * 2.5).to_radians(); // between nodes 2 and 3 (45 deg spacing)
        let (m, s) = f.at_geodetic(100.0 + t, lat.to_radians(), lon, h).unwrap();
        let expect = -20.0 - h / 60e3 + 1e-4 * t + 0.01 * lat + 0.001 * 2.5;
        assert!((m.ln() - expect).abs() < 1e-12, "{} vs {}", m.ln(), expect);
        let rel = 0.1 + 1e-6 * t + 1e-7 * h;
        assert!((s / m - rel).abs() < 1e-12);
    }

    #[test]
    fn repeated_time_node_is_an_exact_step() {
        // ln(mean) = -20 before t = 10 s and -19 from then on, with a linear ramp of
        // 0.01 per second on each side.
        let nodes = vec![0.0, 10.0, 10.0, 20.0];
        let ln_at = [-20.0, -19.9, -19.0, -18.9];
        let mut ln_mean = Vec::new();
        for v in ln_at {
            ln_mean.extend(std::iter::repeat_n(v, 2 * 2 * 3));
        }
        let n = ln_mean.len();
        let f = GriddedField::new(
            0.0,
            nodes,
            (0.0, 1.0, 2),
            (-1.0, 1.0, 2),
            0.0,
            3,
            ln_mean,
            vec![0.1; n],
        )
        .unwrap();
        let ln = |t: f64| f.at_geodetic(t, 0.0, 0.0, 0.5).unwrap().0.ln();
        assert!((ln(5.0) - -19.95).abs() < 1e-12);
        assert!((ln(9.9999) - -19.9).abs() < 1e-5);
        assert!((ln(10.0 - 1e-7) - -19.0).abs() < 1e-12);
        assert!((ln(10.0) - -19.0).abs() < 1e-12);
        assert!((ln(15.0) - -18.95).abs() < 1e-12);
        assert!((ln(20.0) - -18.9).abs() < 1e-12);
        assert!(f.at_geodetic(20.1, 0.0, 0.0, 0.5).is_err());
    }

    #[test]
    fn longitude_is_periodic() {
        let f = affine_field();
        let at = |lon_deg: f64| {
            f.at_geodetic(400.0, 0.1, lon_deg.to_radians(), 350e3)
                .unwrap()
                .0
        };
        // Between the last node (315 deg) and the first (0 deg = 360 deg): linear between
        // the values at io = 7 and io = 0.
        let a = at(315.0).ln();
        let b = at(0.0).ln();
        assert!(((at(337.5).ln()) - 0.5 * (a + b)).abs() < 1e-12);
        assert!((at(-22.5) - at(337.5)).abs() < 1e-25);
        assert!((at(720.0 + 10.0) - at(10.0)).abs() < 1e-25);
    }

    #[test]
    fn a_sigma_scale_multiplies_every_sigma_and_no_mean() {
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let f = affine_field();
        let g = f
            .with_sigma_scale(2.5)
            .unwrap()
            .with_sigma_scale(0.5)
            .unwrap();
        let rot = EarthRotation::new(0.7);
        for k in 0..20 {
            let fixed = geodetic_to_fixed(Geodetic {
                lat: (-50.0 + 5.0 * k as f64).to_radians(),
                lon: (11.0 * k as f64).to_radians(),
                alt: 320e3 + 4e3 * k as f64,
            });
            let r = rot.to_inertial(fixed);
            let ut1 = 100.0 + 50.0 * k as f64;
            let (m, s) = f.mean_sigma(ut1, r, &rot).unwrap();
            let (mg, sg) = g.mean_sigma(ut1, r, &rot).unwrap();
            assert_eq!(m.to_bits(), mg.to_bits());
            assert!((sg / s - 1.25).abs() < 1e-15, "{k}: {}", sg / s);
            let one = |v: f64| [v; 4];
            let lanes = |field: &GriddedField| {
                let (mut ml, mut sl) = ([0.0; 4], [0.0; 4]);
                field
                    .mean_sigma_lanes(
                        ut1,
                        &one(r[0]),
                        &one(r[1]),
                        &one(r[2]),
                        &one(1.0),
                        &rot,
                        &mut ml,
                        &mut sl,
                        &mut LaneMemory::default(),
                    )
                    .unwrap();
                (ml, sl)
            };
            let ((ml, sl), (mgl, sgl)) = (lanes(&f), lanes(&g));
            assert_eq!(ml[2].to_bits(), mgl[2].to_bits());
            assert!((sgl[1] / sl[1] - 1.25).abs() < 1e-15);
        }
        for bad in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(f.with_sigma_scale(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn lane_lookup_agrees_with_the_scalar_one() {
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let f = affine_field();
        let rot = EarthRotation::new(1.234);
        for k in 0..50 {
            let lat = (-55.0 + 2.2 * k as f64).to_radians();
            let lon = (7.3 * k as f64).to_radians();
            let alt = 310e3 + 2.7e3 * k as f64;
            let fixed = geodetic_to_fixed(Geodetic { lat, lon, alt });
            let r = rot.to_inertial(fixed);
            let ut1 = 100.0 + 20.0 * k as f64;
            let (m, s) = f.mean_sigma(ut1, r, &rot).unwrap();
            let (mut ml, mut sl) = ([0.0; 8], [0.0; 8]);
            let one = |v: f64| [v; 8];
            f.mean_sigma_lanes(
                ut1,
                &one(r[0]),
                &one(r[1]),
                &one(r[2]),
                &one(1.0),
                &rot,
                &mut ml,
                &mut sl,
                &mut LaneMemory::default(),
            )
            .unwrap();
            assert!(((ml[3] - m) / m).abs() < LANE_TOL, "{k}: {} vs {m}", ml[3]);
            assert!(((sl[7] - s) / s).abs() < LANE_TOL, "{k}");
        }
        // A lane outside the grid raises the scalar lookup's error; an inactive one is
        // skipped.
        let below = rot.to_inertial(geodetic_to_fixed(Geodetic {
            lat: 0.1,
            lon: 0.2,
            alt: 100e3,
        }));
        let (mut ml, mut sl) = ([0.0; 2], [0.0; 2]);
        let xs = [below[0], below[0]];
        let ys = [below[1], below[1]];
        let zs = [below[2], below[2]];
        let e = f
            .mean_sigma_lanes(
                300.0,
                &xs,
                &ys,
                &zs,
                &[0.0, 1.0],
                &rot,
                &mut ml,
                &mut sl,
                &mut LaneMemory::default(),
            )
            .unwrap_err();
        assert!(e.to_string().contains("altitude"), "{e}");
        f.mean_sigma_lanes(
            300.0,
            &xs,
            &ys,
            &zs,
            &[0.0, 0.0],
            &rot,
            &mut ml,
            &mut sl,
            &mut LaneMemory::default(),
        )
        .unwrap();
    }

    #[test]
    fn every_batch_width_gives_each_lane_the_same_bits() {
        // A trajectory (1 lane), a Monte Carlo batch (8) and a CCSP batch (18) give each
        // lane the same bits; an inactive lane outside the grid gets zero mean and sigma.
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let f = affine_field();
        let rot = EarthRotation::new(0.77);
        let pos = |k: usize| {
            let alt = if k == 5 {
                100e3
            } else {
                305e3 + 9.1e3 * k as f64
            };
            rot.to_inertial(geodetic_to_fixed(Geodetic {
                lat: (-58.0 + 6.9 * k as f64).to_radians(),
                lon: (23.0 * k as f64).to_radians(),
                alt,
            }))
        };
        let active = |k: usize| if k == 5 { 0.0 } else { 1.0 };
        fn run<const W: usize>(
            f: &GriddedField,
            rot: &EarthRotation,
            pos: impl Fn(usize) -> [f64; 3],
            active: impl Fn(usize) -> f64,
        ) -> ([f64; W], [f64; W]) {
            let (x, y, z) = (
                std::array::from_fn(|l| pos(l)[0]),
                std::array::from_fn(|l| pos(l)[1]),
                std::array::from_fn(|l| pos(l)[2]),
            );
            let (mut m, mut s) = ([f64::NAN; W], [f64::NAN; W]);
            let on = std::array::from_fn(&active);
            f.mean_sigma_lanes(
                410.0,
                &x,
                &y,
                &z,
                &on,
                rot,
                &mut m,
                &mut s,
                &mut LaneMemory::default(),
            )
            .unwrap();
            (m, s)
        }
        let (m8, s8) = run::<8>(&f, &rot, pos, active);
        let (m18, s18) = run::<18>(&f, &rot, |k| pos(k % 8), |k| active(k % 8));
        for l in 0..18 {
            assert_eq!(m18[l].to_bits(), m8[l % 8].to_bits(), "lane {l}");
            assert_eq!(s18[l].to_bits(), s8[l % 8].to_bits(), "lane {l}");
            let (m1, s1) = run::<1>(&f, &rot, |_| pos(l % 8), |_| active(l % 8));
            assert_eq!(m1[0].to_bits(), m8[l % 8].to_bits(), "lane {l}");
            assert_eq!(s1[0].to_bits(), s8[l % 8].to_bits(), "lane {l}");
        }
        assert!(m8[0] > 0.0 && m8[5] == 0.0 && s8[5] == 0.0);
    }

    #[test]
    fn time_cell_from_a_hint_is_the_searched_one() {
        // Repeated nodes (jumps) included; every hint, times on, near and between nodes.
        let nodes =
            TimeNodes::checked(vec![0.0, 600.0, 600.0, 1200.0, 1800.0, 1800.0, 2400.0]).unwrap();
        for k in 0..=2600 {
            let t = -100.0 + k as f64 + if k % 3 == 0 { -0.5e-6 } else { 0.0 };
            let want = nodes.locate(t);
            for hint0 in 0..8 {
                let mut hint = hint0;
                let got = nodes.locate_near(t, &mut hint);
                assert_eq!(
                    got.map(|(i, f)| (i, f.to_bits())),
                    want.map(|(i, f)| (i, f.to_bits())),
                    "t {t} hint {hint0}"
                );
            }
        }
    }

    #[test]
    fn kept_corners_give_the_bits_of_a_fresh_lookup() {
        // A batch walking through the field (staying in a cell, crossing cells and the
        // time cell at 600 s, one lane leaving the grid) with its memory gets exactly
        // what a lookup with fresh memory gets at every call: lanes far apart (each its
        // own cell) and lanes close together (mostly one cell, entered together, split
        // when a cell edge falls between them).
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let f = affine_field();
        for (d_lat, d_lon, d_alt) in [(1.0, 40.0, 5e3), (0.05, 0.3, 200.0)] {
            let mut memory = LaneMemory::<8>::default();
            for k in 0..60 {
                let ut1 = 100.0 + 19.0 * k as f64;
                let rot = EarthRotation::new(0.01 * k as f64);
                let pos: [[f64; 3]; 8] = std::array::from_fn(|l| {
                    let alt = if l == 2 && k % 9 == 4 {
                        100e3
                    } else {
                        305e3 + 1.3e3 * k as f64 + d_alt * l as f64
                    };
                    rot.to_inertial(geodetic_to_fixed(Geodetic {
                        lat: (-50.0 + 1.7 * k as f64 + d_lat * l as f64).to_radians(),
                        lon: (3.1 * k as f64 + d_lon * l as f64).to_radians(),
                        alt,
                    }))
                });
                let (x, y, z) = (pos.map(|p| p[0]), pos.map(|p| p[1]), pos.map(|p| p[2]));
                let on = std::array::from_fn(|l| if l == 2 { 0.0 } else { 1.0 });
                let (mut m, mut s) = ([0.0; 8], [0.0; 8]);
                let (mut m0, mut s0) = ([0.0; 8], [0.0; 8]);
                f.mean_sigma_lanes(ut1, &x, &y, &z, &on, &rot, &mut m, &mut s, &mut memory)
                    .unwrap();
                let fresh = &mut LaneMemory::default();
                f.mean_sigma_lanes(ut1, &x, &y, &z, &on, &rot, &mut m0, &mut s0, fresh)
                    .unwrap();
                for l in 0..8 {
                    assert_eq!(m[l].to_bits(), m0[l].to_bits(), "{d_lon} call {k} lane {l}");
                    assert_eq!(s[l].to_bits(), s0[l].to_bits(), "{d_lon} call {k} lane {l}");
                    // and the values themselves: the scalar lookup's, to the lane
                    // conversion's tolerance (zero outside the grid: lane 2 at 100 km)
                    if l != 2 || k % 9 != 4 {
                        let (ms, ss) = f.mean_sigma(ut1, pos[l], &rot).unwrap();
                        assert!((m[l] / ms - 1.0).abs() < LANE_TOL, "call {k} lane {l}");
                        assert!((s[l] / ss - 1.0).abs() < LANE_TOL, "call {k} lane {l}");
                    }
                }
            }
        }
    }

    #[test]
    fn outside_the_grid_is_an_error_naming_the_axis() {
        let f = affine_field();
        let e = f.at_geodetic(100.0 + 1300.0, 0.0, 0.0, 350e3).unwrap_err();
        assert!(e.to_string().contains("time"), "{e}");
        let e = f.at_geodetic(100.0, 0.0, 0.0, 460e3).unwrap_err();
        assert!(e.to_string().contains("altitude (m) = 460000"), "{e}");
        let e = f
            .at_geodetic(100.0, 70f64.to_radians(), 0.0, 350e3)
            .unwrap_err();
        assert!(e.to_string().contains("latitude (deg)"), "{e}");
        // Exactly on the upper corners is inside.
        assert!(f
            .at_geodetic(100.0 + 1200.0, 60f64.to_radians(), 0.0, 450e3)
            .is_ok());
        // A diverged state is not a place outside the field: the message says so.
        let e = f.at_geodetic(100.0, 0.0, 0.0, f64::NAN).unwrap_err();
        assert!(e.to_string().contains("position became non-finite"), "{e}");
    }

    #[test]
    fn rejects_bad_construction() {
        let ok = |v: Vec<f64>| {
            GriddedField::new(
                0.0,
                vec![0.0, 1.0],
                (0.0, 1.0, 2),
                (-1.0, 1.0, 2),
                0.0,
                3,
                v.clone(),
                vec![0.1; 24],
            )
        };
        assert!(ok(vec![0.0; 24]).is_ok());
        assert!(ok(vec![0.0; 23]).is_err());
        let mut nan = vec![0.0; 24];
        nan[5] = f64::NAN;
        assert!(ok(nan).unwrap_err().to_string().contains("ln_mean[5]"));
        assert!(GriddedField::new(
            0.0,
            vec![0.0, 1.0],
            (0.0, 1.0, 2),
            (80.0, 20.0, 2),
            0.0,
            3,
            vec![0.0; 24],
            vec![0.1; 24]
        )
        .is_err());
        let time = |nodes: Vec<f64>| {
            let n = nodes.len();
            GriddedField::new(
                0.0,
                nodes,
                (0.0, 1.0, 2),
                (-1.0, 1.0, 2),
                0.0,
                3,
                vec![0.0; 12 * n],
                vec![0.1; 12 * n],
            )
        };
        assert!(time(vec![0.0, 1.0, 1.0, 2.0]).is_ok());
        assert!(time(vec![0.0, 1.0, 0.5])
            .unwrap_err()
            .to_string()
            .contains("must not decrease"));
        assert!(time(vec![0.0, 1.0, 1.0, 1.0, 2.0]).is_err());
        assert!(time(vec![0.0, 0.0, 2.0]).is_err());
    }

    /// The affine field's values on time nodes `nodes` (s), as one tile.
    fn affine_tile(nodes: &[f64]) -> FieldTile {
        let (na, nl, no) = (4, 5, 8);
        let mut ln_mean = Vec::new();
        let mut rel = Vec::new();
        for &t in nodes {
            for ia in 0..na {
                for il in 0..nl {
                    for io in 0..no {
                        let h = 300e3 + ia as f64 * 50e3;
                        let lat = -60.0 + il as f64 * 30.0;
                        ln_mean.push(-20.0 - h / 60e3 + 1e-4 * t + 0.01 * lat + 0.001 * io as f64);
                        rel.push(0.1 + 1e-6 * t + 1e-7 * h);
                    }
                }
            }
        }
        FieldTile::new(
            nodes.to_vec(),
            (300e3, 50e3, na),
            (-60.0, 30.0, nl),
            0.0,
            no,
            ln_mean,
            rel,
        )
        .unwrap()
    }

    #[test]
    fn tiles_give_the_bits_of_one_field_with_the_same_nodes() {
        // Two tiles meeting at 600 s against one field whose time axis repeats 600 s:
        // the same lookups, scalar and lanes, bit for bit.
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let tiles = vec![
            Arc::new(affine_tile(&[0.0, 300.0, 600.0])),
            Arc::new(affine_tile(&[600.0, 1200.0])),
        ];
        let tiled = GriddedField::from_tiles(100.0, tiles, false).unwrap();
        let whole = {
            let t = affine_tile(&[0.0, 300.0, 600.0, 600.0, 1200.0]);
            GriddedField::from_tiles(100.0, vec![Arc::new(t)], false).unwrap()
        };
        let mut m1 = LaneMemory::<8>::default();
        let mut m2 = LaneMemory::<8>::default();
        for k in 0..80 {
            let ut1 = 100.0 + 15.0 * k as f64;
            let rot = EarthRotation::new(0.02 * k as f64);
            let pos: [[f64; 3]; 8] = std::array::from_fn(|l| {
                rot.to_inertial(geodetic_to_fixed(Geodetic {
                    lat: (-50.0 + 1.1 * k as f64 + l as f64).to_radians(),
                    lon: (4.1 * k as f64 + 40.0 * l as f64).to_radians(),
                    alt: 305e3 + 1.3e3 * k as f64 + 2e3 * l as f64,
                }))
            });
            let (x, y, z) = (pos.map(|p| p[0]), pos.map(|p| p[1]), pos.map(|p| p[2]));
            let on = [1.0; 8];
            let (mut a, mut b) = ([0.0; 8], [0.0; 8]);
            let (mut c, mut d) = ([0.0; 8], [0.0; 8]);
            tiled
                .mean_sigma_lanes(ut1, &x, &y, &z, &on, &rot, &mut a, &mut b, &mut m1)
                .unwrap();
            whole
                .mean_sigma_lanes(ut1, &x, &y, &z, &on, &rot, &mut c, &mut d, &mut m2)
                .unwrap();
            for l in 0..8 {
                assert_eq!(a[l].to_bits(), c[l].to_bits(), "call {k} lane {l}");
                assert_eq!(b[l].to_bits(), d[l].to_bits(), "call {k} lane {l}");
                let (ms, ss) = tiled.mean_sigma(ut1, pos[l], &rot).unwrap();
                let (mw, sw) = whole.mean_sigma(ut1, pos[l], &rot).unwrap();
                assert_eq!((ms.to_bits(), ss.to_bits()), (mw.to_bits(), sw.to_bits()));
            }
        }
    }

    #[test]
    fn tiles_must_follow_each_other_on_one_grid() {
        let gap = GriddedField::from_tiles(
            0.0,
            vec![
                Arc::new(affine_tile(&[0.0, 600.0])),
                Arc::new(affine_tile(&[700.0, 1200.0])),
            ],
            false,
        )
        .unwrap_err();
        assert!(
            gap.to_string().contains("must equal the end of tile 0"),
            "{gap}"
        );
        let other = FieldTile::new(
            vec![600.0, 1200.0],
            (300e3, 25e3, 2),
            (-60.0, 30.0, 5),
            0.0,
            8,
            vec![0.0; 160],
            vec![0.1; 160],
        )
        .unwrap();
        let e = GriddedField::from_tiles(
            0.0,
            vec![Arc::new(affine_tile(&[0.0, 600.0])), Arc::new(other)],
            false,
        )
        .unwrap_err();
        assert!(e.to_string().contains("another altitude"), "{e}");
        assert!(GriddedField::from_tiles(0.0, vec![], false).is_err());
    }

    #[test]
    fn above_the_top_ln_mean_follows_the_top_slope_and_sigma_is_held() {
        // The affine field tops out at 450 km; ln(mean) falls by 1 per 60 km, so above the
        // top the extrapolation is exact, and sigma/mean keeps its value at 450 km.
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let tile = Arc::new(affine_tile(&[0.0, 600.0, 1200.0]));
        let f = GriddedField::from_tiles(100.0, vec![tile.clone()], true).unwrap();
        let strict = GriddedField::from_tiles(100.0, vec![tile], false).unwrap();
        let (t, lat) = (500.0, 12.0f64);
        for h in [450e3, 450e3 + 1.0, 600e3, 1500e3, 36000e3] {
            let (m, s) = f.at_geodetic(100.0 + t, lat.to_radians(), 0.0, h).unwrap();
            let expect = -20.0 - h / 60e3 + 1e-4 * t + 0.01 * lat;
            assert!(
                (m.ln() - expect).abs() < 1e-9,
                "{h}: {} vs {expect}",
                m.ln()
            );
            let rel = 0.1 + 1e-6 * t + 1e-7 * 450e3;
            assert!((s / m - rel).abs() < 1e-12, "{h}");
        }
        assert!(strict.at_geodetic(600.0, 0.2, 0.0, 460e3).is_err());
        // Lanes above the top: the scalar value, and the bits of every batch width.
        let rot = EarthRotation::new(0.3);
        let pos = |l: usize| {
            rot.to_inertial(geodetic_to_fixed(Geodetic {
                lat: (-40.0 + 9.0 * l as f64).to_radians(),
                lon: (30.0 * l as f64).to_radians(),
                alt: 420e3 + 200e3 * l as f64,
            }))
        };
        let (x, y, z): ([f64; 8], [f64; 8], [f64; 8]) = (
            std::array::from_fn(|l| pos(l)[0]),
            std::array::from_fn(|l| pos(l)[1]),
            std::array::from_fn(|l| pos(l)[2]),
        );
        let (mut m, mut s) = ([0.0; 8], [0.0; 8]);
        f.mean_sigma_lanes(
            700.0,
            &x,
            &y,
            &z,
            &[1.0; 8],
            &rot,
            &mut m,
            &mut s,
            &mut LaneMemory::default(),
        )
        .unwrap();
        for l in 0..8 {
            let (ms, ss) = f.mean_sigma(700.0, pos(l), &rot).unwrap();
            assert!(
                ((m[l] - ms) / ms).abs() < LANE_TOL,
                "lane {l}: {} vs {ms}",
                m[l]
            );
            assert!(((s[l] - ss) / ss).abs() < LANE_TOL, "lane {l}");
        }
    }

    #[test]
    fn below_the_bottom_an_open_field_holds_the_bottom_level() {
        // Scalar and lane lookups below an open field's bottom (300 km) read the values at
        // 300 km; a closed field still refuses.
        use crate::frames::{geodetic_to_fixed, Geodetic};
        let tile = Arc::new(affine_tile(&[0.0, 600.0, 1200.0]));
        let open = GriddedField::from_tiles(100.0, vec![tile.clone()], true).unwrap();
        let closed = GriddedField::from_tiles(100.0, vec![tile], false).unwrap();
        let at = |h: f64| open.at_geodetic(600.0, 0.3, 0.4, h).unwrap();
        assert_eq!(at(-5e3), at(300e3));
        assert_eq!(at(299e3), at(300e3));
        assert!(closed.at_geodetic(600.0, 0.3, 0.4, 299e3).is_err());
        let rot = EarthRotation::new(0.2);
        let r = rot.to_inertial(geodetic_to_fixed(Geodetic {
            lat: 0.3,
            lon: 0.9,
            alt: 50e3,
        }));
        let (mut m, mut sg) = ([0.0; 8], [0.0; 8]);
        open.mean_sigma_lanes(
            600.0,
            &[r[0]; 8],
            &[r[1]; 8],
            &[r[2]; 8],
            &[1.0; 8],
            &rot,
            &mut m,
            &mut sg,
            &mut LaneMemory::default(),
        )
        .unwrap();
        let (ms, ss) = open.mean_sigma(600.0, r, &rot).unwrap();
        assert!(((m[0] - ms) / ms).abs() < LANE_TOL && ((sg[5] - ss) / ss).abs() < LANE_TOL);
    }
}
