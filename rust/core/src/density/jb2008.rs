//! Jacchia-Bowman 2008 (JB2008) thermospheric density, point evaluation.
//!
//! The model is the CIRA "integration form" of a Jacchia model with the JB2008 changes
//! (Bowman et al. 2008, "A New Empirical Thermospheric Density Model JB2008 Using New
//! Solar and Geomagnetic Indices", AIAA 2008-6438): the exospheric temperature from the
//! solar indices F10, S10, M10, Y10 and their 81-day centred means, the Dst-derived storm
//! temperature change dTc, the local-time/latitude correction of dTc, the barometric and
//! diffusion equations integrated with five-point Newton-Cotes steps from 90 km, the J70
//! seasonal-latitudinal term, the JB2008 semiannual term and the exospheric correction
//! above 1000 km. Written from the equations of the reference Fortran (Bowman, 2008;
//! distributed by Space Environment Technologies) so that it reproduces the reference to
//! rounding: the constants are the reference's, including its short values of pi.
//!
//! [`sun_position`] and [`greenwich_angle`] are the reference driver's own Sun position
//! (Astronomical Almanac low-precision formulae) and Greenwich right ascension (THETA,
//! days since 1950), which JB2008 was fitted and is tested with; [`density_geodetic`]
//! uses them to turn a UTC epoch, geodetic latitude, longitude and altitude into the
//! inputs of [`jb2008`].

use crate::error::{finite, CoreError};

/// Lowest altitude the model is defined at, km (the integration starts at 90 km).
pub const FLOOR_KM: f64 = 90.0;

/// Modified Julian date of 1950 January 0.0 (the reference's D1950 origin): MJD - 33281.
pub const MJD_1950: f64 = 33281.0;

/// The solar and geomagnetic drivers of one evaluation (with the reference's lags
/// already applied by the caller): F10, S10, M10 and Y10 (sfu-scaled) and their 81-day
/// centred means, and the storm temperature change dTc (K).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jb2008Indices {
    pub f10: f64,
    pub f10b: f64,
    pub s10: f64,
    pub s10b: f64,
    pub m10: f64,
    pub m10b: f64,
    pub y10: f64,
    pub y10b: f64,
    pub dstdtc: f64,
}

impl Jb2008Indices {
    /// Names of the fields in order (for error messages and array columns).
    pub const NAMES: [&'static str; 9] = [
        "F10", "F10B", "S10", "S10B", "M10", "M10B", "Y10", "Y10B", "DSTDTC",
    ];

    /// From the nine values in [`Jb2008Indices::NAMES`] order.
    pub fn from_array(v: [f64; 9]) -> Self {
        Self {
            f10: v[0],
            f10b: v[1],
            s10: v[2],
            s10b: v[3],
            m10: v[4],
            m10b: v[5],
            y10: v[6],
            y10b: v[7],
            dstdtc: v[8],
        }
    }

    fn as_array(&self) -> [f64; 9] {
        [
            self.f10,
            self.f10b,
            self.s10,
            self.s10b,
            self.m10,
            self.m10b,
            self.y10,
            self.y10b,
            self.dstdtc,
        ]
    }

    /// Checks that every value is finite and the solar indices positive.
    pub fn validate(&self) -> Result<(), CoreError> {
        for (name, v) in Self::NAMES.iter().zip(self.as_array()) {
            finite(name, v)?;
            if *name != "DSTDTC" && v <= 0.0 {
                return Err(CoreError::invalid(*name, v, "must be > 0 sfu"));
            }
        }
        Ok(())
    }
}

/// Output of one evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jb2008Output {
    /// Exospheric temperature above the point (without the local-time dTc correction), K.
    pub tinf: f64,
    /// Temperature at the point, K.
    pub temp: f64,
    /// Total mass density, kg/m^3.
    pub rho: f64,
}

// Constants of the reference, with its own short values where it has them (the short
// values of pi, 2 pi, pi/2 and ln 10 are deliberate: they reproduce the reference).
#[allow(clippy::approx_constant)]
const PI_REF: f64 = 3.1415927;
#[allow(clippy::approx_constant)]
const TWOPI_REF: f64 = 6.2831853;
#[allow(clippy::approx_constant)]
const PIOV2_REF: f64 = 1.5707963;
#[allow(clippy::approx_constant)]
const AL10: f64 = 2.3025851;
/// Molecular weights N2, O2, O, Ar, He, H (kg/kmol).
const AMW: [f64; 6] = [28.0134, 31.9988, 15.9994, 39.9480, 4.0026, 1.00797];
/// Thermal diffusion coefficients (only He is non-zero).
const ALPHA: [f64; 5] = [0.0, 0.0, 0.0, 0.0, -0.38];
/// Avogadro's number, molecules/kmol.
const AVOGAD: f64 = 6.02257e26;
/// Sea-level volume fractions N2, O2, Ar, He.
const FRAC: [f64; 4] = [0.78110, 0.20955, 9.3400e-3, 1.2890e-5];
/// Universal gas constant, J/(K kmol).
const RSTAR: f64 = 8314.32;
/// Logarithmic height steps of the regimes 90-105, 105-500 and above 500 km.
const R1: f64 = 0.010;
const R2: f64 = 0.025;
const R3: f64 = 0.075;
/// Five-point Newton-Cotes weights as the reference prints them.
const WT: [f64; 5] = [
    0.311111111111111,
    1.422222222222222,
    0.533333333333333,
    1.422222222222222,
    0.311111111111111,
];
/// High-altitude density correction coefficients.
const CHT: [f64; 4] = [0.22, -0.20e-02, 0.115e-02, -0.211e-05];

/// Mean molecular weight below 105 km (Jacchia's equation 1).
fn xambar(z: f64) -> f64 {
    const C: [f64; 7] = [
        28.15204, -8.5586e-2, 1.2840e-4, -1.0056e-5, -1.0210e-5, 1.5044e-6, 9.9826e-8,
    ];
    let dz = z - 100.0;
    let mut amb = C[6];
    for j in (0..6).rev() {
        amb = dz * amb + C[j];
    }
    amb
}

/// Gravity at height z km (equation 8), m/s^2.
fn xgrav(z: f64) -> f64 {
    let q = 1.0 + z / 6356.766;
    9.80665 / (q * q)
}

/// Temperature profile (equations 10 and 13), K; `tc` = [Tx, Gx, A, Gx/A].
fn xlocal(z: f64, tc: &[f64; 4]) -> f64 {
    let dz = z - 125.0;
    if dz <= 0.0 {
        ((-9.8204695e-6 * dz - 7.3039742e-4) * dz * dz + 1.0) * dz * tc[1] + tc[0]
    } else {
        // dz^2.5 as dz^2 sqrt(dz): the same value to rounding, several times faster.
        tc[0] + tc[2] * (tc[3] * dz * (1.0 + 4.5e-6 * dz * dz * dz.sqrt())).atan()
    }
}

/// Local-solar-time and latitude correction of dTc (the reference's DTSUB), K:
/// `f10` sfu, `xlst` local solar time in hours, `xlat` latitude rad, `zht` height km.
fn dtsub(f10: f64, xlst: f64, xlat: f64, zht: f64) -> f64 {
    const B: [f64; 19] = [
        -0.457512297e+01,
        -0.512114909e+01,
        -0.693003609e+02,
        0.203716701e+03,
        0.703316291e+03,
        -0.194349234e+04,
        0.110651308e+04,
        -0.174378996e+03,
        0.188594601e+04,
        -0.709371517e+04,
        0.922454523e+04,
        -0.384508073e+04,
        -0.645841789e+01,
        0.409703319e+02,
        -0.482006560e+03,
        0.181870931e+04,
        -0.237389204e+04,
        0.996703815e+03,
        0.361416936e+02,
    ];
    const C: [f64; 23] = [
        -0.155986211e+02,
        -0.512114909e+01,
        -0.693003609e+02,
        0.203716701e+03,
        0.703316291e+03,
        -0.194349234e+04,
        0.110651308e+04,
        -0.220835117e+03,
        0.143256989e+04,
        -0.318481844e+04,
        0.328981513e+04,
        -0.135332119e+04,
        0.199956489e+02,
        -0.127093998e+02,
        0.212825156e+02,
        -0.275555432e+01,
        0.110234982e+02,
        0.148881951e+03,
        -0.751640284e+03,
        0.637876542e+03,
        0.127093998e+02,
        -0.212825156e+02,
        0.275555432e+01,
    ];
    let tx = xlst / 24.0;
    let (tx2, tx3) = (tx * tx, tx * tx * tx);
    let (tx4, tx5) = (tx3 * tx, tx3 * tx * tx);
    let ycs = xlat.cos();
    let f = (f10 - 100.0) / 100.0;
    // The 120-240 km polynomial: its part linear in H (times H) and its constant part.
    let c_lin = C[0]
        + B[1] * f
        + C[2] * tx * f
        + C[3] * tx2 * f
        + C[4] * tx3 * f
        + C[5] * tx4 * f
        + C[6] * tx5 * f
        + C[7] * tx * ycs
        + C[8] * tx2 * ycs
        + C[9] * tx3 * ycs
        + C[10] * tx4 * ycs
        + C[11] * tx5 * ycs
        + C[12] * ycs
        + C[13] * f * ycs
        + C[14] * tx * f * ycs
        + C[15] * tx2 * f * ycs;
    let c_const = C[16]
        + C[17] * tx * ycs
        + C[18] * tx2 * ycs
        + C[19] * tx3 * ycs
        + C[20] * f * ycs
        + C[21] * tx * f * ycs
        + C[22] * tx2 * f * ycs;
    // The 300-600 km polynomial in H = z/100 and its derivative in H.
    let b_base = B[0]
        + B[1] * f
        + B[2] * tx * f
        + B[3] * tx2 * f
        + B[4] * tx3 * f
        + B[5] * tx4 * f
        + B[6] * tx5 * f
        + B[7] * tx * ycs
        + B[8] * tx2 * ycs
        + B[9] * tx3 * ycs
        + B[10] * tx4 * ycs
        + B[11] * tx5 * ycs
        + B[18] * ycs;
    let b_slope = B[12] * ycs
        + B[13] * tx * ycs
        + B[14] * tx2 * ycs
        + B[15] * tx3 * ycs
        + B[16] * tx4 * ycs
        + B[17] * tx5 * ycs;
    let b_at = |h: f64| b_base + b_slope * h;
    if (120.0..=200.0).contains(&zht) {
        let dtc200 = c_const;
        let dtc200dz = c_lin;
        let cc = 3.0 * dtc200 - dtc200dz;
        let dd = dtc200 - cc;
        let zp = (zht - 120.0) / 80.0;
        cc * zp * zp + dd * zp * zp * zp
    } else if zht > 200.0 && zht <= 240.0 {
        let h = (zht - 200.0) / 50.0;
        c_lin * h + c_const
    } else if zht > 240.0 && zht <= 300.0 {
        let aa = c_lin * 0.8 + c_const;
        let bb = c_lin;
        let dtc300 = b_at(3.0);
        let dtc300dz = b_slope;
        let cc = 3.0 * dtc300 - dtc300dz - 3.0 * aa - 2.0 * bb;
        let dd = dtc300 - aa - bb - cc;
        let zp = (zht - 240.0) / 60.0;
        aa + bb * zp + cc * zp * zp + dd * zp * zp * zp
    } else if zht > 300.0 && zht <= 600.0 {
        b_at(zht / 100.0)
    } else if zht > 600.0 && zht <= 800.0 {
        let zp = (zht - 600.0) / 100.0;
        let aa = b_at(6.0);
        let bb = b_slope;
        let cc = -(3.0 * aa + 4.0 * bb) / 4.0;
        let dd = (aa + bb) / 4.0;
        aa + bb * zp + cc * zp * zp + dd * zp * zp * zp
    } else {
        0.0
    }
}

/// Semiannual variation (the reference's SEMIAN08): (amplitude FZ, phase function GT,
/// delta log10 rho) at day of year `day` (1.0 at Jan 1 00:00), height `ht` km and the
/// 81-day centred F10, S10, M10.
fn semian08(day: f64, ht: f64, f10b: f64, s10b: f64, m10b: f64) -> (f64, f64, f64) {
    #[allow(clippy::approx_constant)]
    const TWOPI: f64 = 6.2831853072;
    const FZM: [f64; 5] = [0.2689, -0.1176e-01, 0.2782e-01, -0.2782e-01, 0.3470e-03];
    const GTM: [f64; 10] = [
        -0.3633,
        0.8506e-01,
        0.2401,
        -0.1897,
        -0.2554,
        -0.1790e-01,
        0.5650e-03,
        -0.6407e-03,
        -0.3418e-02,
        -0.1252e-02,
    ];
    let fsmb = f10b - 0.70 * s10b - 0.04 * m10b;
    let htz = ht / 1000.0;
    let mut fzz = FZM[0]
        + FZM[1] * fsmb
        + FZM[2] * fsmb * htz
        + FZM[3] * fsmb * htz * htz
        + FZM[4] * fsmb * fsmb * htz;
    let fsmb = f10b - 0.75 * s10b - 0.37 * m10b;
    let tau = (day - 1.0) / 365.0;
    let (sin1p, cos1p) = (TWOPI * tau).sin_cos();
    let (sin2p, cos2p) = (2.0 * TWOPI * tau).sin_cos();
    let gtz = GTM[0]
        + GTM[1] * sin1p
        + GTM[2] * cos1p
        + GTM[3] * sin2p
        + GTM[4] * cos2p
        + GTM[5] * fsmb
        + GTM[6] * fsmb * sin1p
        + GTM[7] * fsmb * cos1p
        + GTM[8] * fsmb * sin2p
        + GTM[9] * fsmb * cos2p;
    if fzz < 1e-6 {
        fzz = 1e-6;
    }
    (fzz, gtz, fzz * gtz)
}

/// Day of year plus fraction (1.0 at Jan 1 00:00) from days since 1950 Jan 0.0, as the
/// reference's TMOUTD computes it (valid 1950-2099).
pub fn day_of_year(d1950: f64) -> f64 {
    let whole = d1950.trunc();
    let frac = d1950 - whole;
    let mut iyday = whole as i64 + 364;
    let four = iyday / 1461;
    iyday -= four * 1461;
    let years = (iyday / 365).min(3);
    iyday = iyday - 365 * years + 1;
    iyday as f64 + frac
}

/// Five-point Newton-Cotes integration of `f` over `n` logarithmic steps from `z0` by the
/// ratio `zr`; returns (integral, last evaluation point, last value of `f`, end point).
#[inline]
fn integrate(
    z0: f64,
    n: usize,
    zr: f64,
    mut ain: f64,
    mut f: impl FnMut(f64) -> f64,
) -> (f64, f64, f64, f64) {
    let mut zend = z0;
    let mut z = z0;
    let mut sum = 0.0;
    for _ in 0..n {
        z = zend;
        zend = zr * z;
        let dz = 0.25 * (zend - z);
        let mut s1 = WT[0] * ain;
        for w in &WT[1..] {
            z += dz;
            ain = f(z);
            s1 += w * ain;
        }
        sum += dz * s1;
    }
    (sum, z, ain, zend)
}

/// Number of steps and step ratio from `z0` to `z1` with logarithmic step `r`.
#[inline]
fn steps(z0: f64, z1: f64, r: f64) -> (usize, f64) {
    let al = (z1 / z0).ln();
    let n = (al / r) as usize + 1;
    (n, (al / n as f64).exp())
}

/// JB2008 at one point, exactly as the reference routine is called: `amjd` modified Julian
/// date (UTC), `sun_ra`/`sun_dec` the Sun's right ascension and declination (rad),
/// `sat_ra` the point's right ascension (rad), `sat_lat` its geodetic latitude (rad, as the
/// reference uses it), `alt_km` its height (km, >= 90), and the drivers.
///
/// Errors (naming the argument) on non-finite input, |latitude| > pi/2, altitude below
/// [`FLOOR_KM`] or non-positive solar indices.
#[allow(clippy::too_many_arguments)]
pub fn jb2008(
    amjd: f64,
    sun_ra: f64,
    sun_dec: f64,
    sat_ra: f64,
    sat_lat: f64,
    alt_km: f64,
    ix: &Jb2008Indices,
) -> Result<Jb2008Output, CoreError> {
    finite("amjd", amjd)?;
    finite("sun_ra", sun_ra)?;
    finite("sun_dec", sun_dec)?;
    finite("sat_ra", sat_ra)?;
    finite("latitude", sat_lat)?;
    finite("altitude", alt_km)?;
    if sat_lat.abs() > std::f64::consts::FRAC_PI_2 * (1.0 + 1e-12) {
        return Err(CoreError::invalid(
            "latitude",
            sat_lat.to_degrees(),
            "must be within -90..90 deg",
        ));
    }
    if alt_km < FLOOR_KM {
        return Err(CoreError::invalid(
            "altitude",
            alt_km * 1e3,
            "is below JB2008's floor of 90 km (90000 m)",
        ));
    }
    ix.validate()?;
    Ok(jb2008_unchecked(
        amjd, sun_ra, sun_dec, sat_ra, sat_lat, alt_km, ix,
    ))
}

#[allow(clippy::too_many_arguments)]
fn jb2008_unchecked(
    amjd: f64,
    sun_ra: f64,
    sun_dec: f64,
    sat_ra: f64,
    sat_lat: f64,
    alt_km: f64,
    ix: &Jb2008Indices,
) -> Jb2008Output {
    let degrad = PI_REF / 180.0;
    // Equation (14): the nighttime minimum exospheric temperature from the solar indices.
    let fn_ = (ix.f10b / 240.0).sqrt().sqrt().min(1.0);
    let fsb = ix.f10b * fn_ + ix.s10b * (1.0 - fn_);
    let tsubc = 392.4
        + 3.227 * fsb
        + 0.298 * (ix.f10 - ix.f10b)
        + 2.259 * (ix.s10 - ix.s10b)
        + 0.312 * (ix.m10 - ix.m10b)
        + 0.178 * (ix.y10 - ix.y10b);
    // Equations (15)-(17): the diurnal variation.
    let eta = 0.5 * (sat_lat - sun_dec).abs();
    let theta = 0.5 * (sat_lat + sun_dec).abs();
    let h = sat_ra - sun_ra;
    let tau = h - 0.64577182 + 0.10471976 * (h + 0.75049158).sin();
    let mut glsthr = ((h + PI_REF) / degrad) * (24.0 / 360.0);
    if glsthr >= 24.0 {
        glsthr -= 24.0;
    }
    if glsthr < 0.0 {
        glsthr += 24.0;
    }
    let pow25 = |x: f64| x * x * x.sqrt();
    let c = pow25(eta.cos());
    let s = pow25(theta.sin());
    let df = s + (c - s) * (0.5 * tau).cos().abs().powi(3);
    let tsubl = tsubc * (1.0 + 0.31 * df);
    let dtclst = dtsub(ix.f10, glsthr, sat_lat, alt_km);
    let tinf_out = tsubl + ix.dstdtc;
    let tinf = tsubl + ix.dstdtc + dtclst;
    // Equations (9), (11), (13): the temperature profile.
    let tsubx = 444.3807 + 0.02385 * tinf - 392.8292 * (-0.0021357 * tinf).exp();
    let gsubx = 0.054285714 * (tsubx - 183.0);
    let tc3 = (tinf - tsubx) / PIOV2_REF;
    let tc = [tsubx, gsubx, tc3, gsubx / tc3];

    // Equation (5): the barometric equation from 90 km to min(z, 105 km).
    let z1 = 90.0;
    let (n, zr) = steps(z1, alt_km.min(105.0), R1);
    let ambar1 = xambar(z1);
    let tloc1 = xlocal(z1, &tc);
    let ain0 = ambar1 * xgrav(z1) / tloc1;
    let mut ambar2 = 0.0;
    let mut tloc2 = 0.0;
    let mut gravl = 0.0;
    let (sum2, mut z, _, mut zend) = integrate(z1, n, zr, ain0, |zz| {
        ambar2 = xambar(zz);
        tloc2 = xlocal(zz, &tc);
        gravl = xgrav(zz);
        ambar2 * gravl / tloc2
    });
    let fact1 = 1000.0 / RSTAR;
    let rho = 3.46e-6 * ambar2 * tloc1 * (-fact1 * sum2).exp() / ambar1 / tloc2;
    // Equations (2)-(4): number densities at the top of the mixed region.
    let anm = AVOGAD * rho;
    let an = anm / ambar2;
    let fact2 = anm / 28.960;
    let mut aln = [0.0; 6];
    aln[0] = (FRAC[0] * fact2).ln();
    aln[3] = (FRAC[2] * fact2).ln();
    aln[4] = (FRAC[3] * fact2).ln();
    aln[1] = (fact2 * (1.0 + FRAC[1]) - an).ln();
    aln[2] = (2.0 * (an - fact2)).ln();

    let temp;
    if alt_km <= 105.0 {
        temp = tloc2;
        // Negligible hydrogen.
        aln[5] = aln[4] - 25.0;
    } else {
        // Equation (6): the diffusion equation from 105 km to min(z, 500) and on to z.
        let (n, zr) = steps(z, alt_km.min(500.0), R2);
        let mut tloc3 = 0.0;
        let ain = gravl / tloc2;
        let (sum2, z_b, ain_b, zend_b) = integrate(zend, n, zr, ain, |zz| {
            tloc3 = xlocal(zz, &tc);
            gravl = xgrav(zz);
            gravl / tloc3
        });
        z = z_b;
        zend = zend_b;
        let r = if alt_km > 500.0 { R3 } else { R2 };
        let (n, zr) = steps(z, alt_km.max(500.0), r);
        let mut tloc4 = 0.0;
        let (sum3, z_c, _, _) = integrate(zend, n, zr, ain_b, |zz| {
            tloc4 = xlocal(zz, &tc);
            gravl = xgrav(zz);
            gravl / tloc4
        });
        z = z_c;
        let (altr, fact2, hsign);
        if alt_km <= 500.0 {
            temp = tloc3;
            altr = (tloc3 / tloc2).ln();
            fact2 = fact1 * sum2;
            hsign = 1.0;
        } else {
            temp = tloc4;
            altr = (tloc4 / tloc2).ln();
            fact2 = fact1 * (sum2 + sum3);
            hsign = -1.0;
        }
        for i in 0..5 {
            aln[i] = aln[i] - (1.0 + ALPHA[i]) * altr - fact2 * AMW[i];
        }
        // Equation (7): hydrogen.
        let al10t5 = tinf.log10();
        let alnh5 = (5.5 * al10t5 - 39.40) * al10t5 + 73.13;
        aln[5] = AL10 * (alnh5 + 6.0) + hsign * ((tloc4 / tloc3).ln() + fact1 * sum3 * AMW[5]);
    }

    // Equation (24): the J70 seasonal-latitudinal variation.
    let trash = (amjd - 36204.0) / 365.2422;
    let capphi = trash % 1.0;
    let sign_lat = if sat_lat.is_sign_negative() {
        -1.0
    } else {
        1.0
    };
    let sl = sat_lat.sin();
    let dlrsl = 0.02
        * (alt_km - 90.0)
        * (-0.045 * (alt_km - 90.0)).exp()
        * sign_lat
        * (TWOPI_REF * capphi + 1.72).sin()
        * sl
        * sl;
    // Equation (23): the semiannual variation.
    let mut dlrsa = 0.0;
    if z < 2000.0 {
        let yrday = day_of_year(amjd - MJD_1950);
        let (fzz, _gtz, dl) = semian08(yrday, alt_km, ix.f10b, ix.s10b, ix.m10b);
        dlrsa = if fzz < 0.0 { 0.0 } else { dl };
    }
    let dlr = AL10 * (dlrsl + dlrsa);
    let mut sumnm = 0.0;
    for (a, w) in aln.iter().zip(AMW) {
        sumnm += (a + dlr).exp() * w;
    }
    let mut rho = sumnm / AVOGAD;
    // The exospheric correction above 1000 km.
    let zht = alt_km;
    let mut fex = 1.0;
    if (1000.0..1500.0).contains(&zht) {
        let zeta = (zht - 1000.0) * 0.002;
        let f15c = CHT[0] + CHT[1] * ix.f10b + CHT[2] * 1500.0 + CHT[3] * ix.f10b * 1500.0;
        let f15c_zeta = (CHT[2] + CHT[3] * ix.f10b) * 500.0;
        let fex2 = 3.0 * f15c - f15c_zeta - 3.0;
        let fex3 = f15c_zeta - 2.0 * f15c + 2.0;
        fex = 1.0 + fex2 * zeta * zeta + fex3 * zeta * zeta * zeta;
    }
    if zht >= 1500.0 {
        fex = CHT[0] + CHT[1] * ix.f10b + CHT[2] * zht + CHT[3] * ix.f10b * zht;
    }
    rho *= fex;
    Jb2008Output {
        tinf: tinf_out,
        temp,
        rho,
    }
}

/// Sun right ascension and declination (rad) at modified Julian date `amjd` (UTC), with
/// the reference driver's formulae (Astronomical Almanac, low precision, 0.01 deg
/// 1950-2050): mean anomaly g = 357.528 + 0.9856003 d, mean longitude
/// L = 280.460 + 0.9856474 d (d days from J2000.0 = MJD 51544.5), ecliptic longitude
/// lambda = L + 1.915 sin g + 0.020 sin 2g, obliquity eps = 23.439 - 4e-7 d, and
/// RA = lambda - tan^2(eps/2) sin 2 lambda + tan^4(eps/2)/2 sin 4 lambda,
/// Dec = asin(sin eps sin lambda). The rates are single-precision literals in the
/// reference and are used as such.
pub fn sun_position(amjd: f64) -> (f64, f64) {
    use std::f64::consts::PI;
    let degrad = PI / 180.0;
    let d2000 = amjd - 51544.5;
    let solan = (357.528 + f64::from(0.9856003_f32) * d2000) * degrad;
    let mut solon = (280.460 + f64::from(0.9856474_f32) * d2000) % 360.0;
    if solon < 0.0 {
        solon += 360.0;
    }
    let eclon = (solon + 1.915 * solan.sin() + 0.02 * (2.0 * solan).sin()) * degrad;
    let eps = (23.439 - f64::from(0.0000004_f32) * d2000) * degrad;
    let t1 = (0.5 * eps).tan();
    let t2 = t1 * t1;
    let t4 = t2 * t2;
    let mut ra = eclon - t2 * (2.0 * eclon).sin() + 0.5 * t4 * (4.0 * eclon).sin();
    if ra < 0.0 {
        ra += 2.0 * PI;
    } else if ra > 2.0 * PI {
        ra -= 2.0 * PI;
    }
    let dec = (eps.sin() * eclon.sin()).asin();
    (ra, dec)
}

/// Right ascension of Greenwich (rad, 0..2pi) at `d1950` days since 1950 Jan 0.0 UTC, the
/// reference driver's THETA: after 1970,
/// `1.73213438565 + 1.720279169407e-2 N + (1.720279169407e-2 + 2 pi) f + 5.0755141943e-15 T^2`
/// with T days since 1970 Jan 0.0, N its whole days and f the fraction (before 1970 the
/// driver's 1950 series).
pub fn greenwich_angle(d1950: f64) -> f64 {
    use std::f64::consts::TAU;
    let nday = d1950.trunc();
    let mut theta = if nday <= 7305.0 {
        let tfrac = d1950 - nday;
        (1.7294446614 + 1.72027915246e-2 * nday + 6.3003880926 * tfrac) % TAU
    } else {
        let ts70 = d1950 - 7305.0;
        let ids70 = ts70.trunc();
        let tfrac = ts70 - ids70;
        (1.73213438565
            + 1.720279169407e-2 * ids70
            + (1.720279169407e-2 + TAU) * tfrac
            + 5.0755141943e-15 * ts70 * ts70)
            % TAU
    };
    if theta < 0.0 {
        theta += TAU;
    }
    theta
}

/// JB2008 at a UTC epoch (`amjd`, modified Julian date), geodetic latitude and longitude
/// (deg) and altitude (m), with the Sun position of [`sun_position`] and the point's right
/// ascension Greenwich angle ([`greenwich_angle`]) + longitude, as the reference driver
/// computes them. The geodetic latitude is used as the model's latitude (as the
/// reference driver does).
pub fn density_geodetic(
    amjd: f64,
    lat_deg: f64,
    lon_deg: f64,
    alt_m: f64,
    ix: &Jb2008Indices,
) -> Result<Jb2008Output, CoreError> {
    use std::f64::consts::TAU;
    finite("time", amjd)?;
    finite("latitude", lat_deg)?;
    finite("longitude", lon_deg)?;
    finite("altitude", alt_m)?;
    if lat_deg.abs() > 90.0 {
        return Err(CoreError::invalid(
            "latitude",
            lat_deg,
            "must be within -90..90 deg",
        ));
    }
    if alt_m < FLOOR_KM * 1e3 {
        return Err(CoreError::invalid(
            "altitude",
            alt_m,
            "is below JB2008's floor of 90 km (90000 m)",
        ));
    }
    let (sun_ra, sun_dec) = sun_position(amjd);
    let sat_ra = (greenwich_angle(amjd - MJD_1950) + lon_deg.to_radians()).rem_euclid(TAU);
    jb2008(
        amjd,
        sun_ra,
        sun_dec,
        sat_ra,
        lat_deg.to_radians(),
        alt_m / 1e3,
        ix,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quiet() -> Jb2008Indices {
        Jb2008Indices::from_array([70.0, 72.0, 60.0, 62.0, 65.0, 68.0, 60.0, 62.0, 0.0])
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    // Direct calls of the reference Fortran routine (from the reference-data subset
    // documented in shared/data/reference/density_reference_values.json).
    #[test]
    fn matches_reference_core_calls() {
        type Case = (f64, [f64; 5], f64, [f64; 9], [f64; 3]);
        let cases: [Case; 3] = [
            (
                52521.25,
                [
                    2.844492633827471,
                    0.1262429153207661,
                    3.649698864601041,
                    0.8149188217481991,
                    90.0,
                ],
                0.0,
                [70.0, 72.0, 60.0, 62.0, 65.0, 68.0, 60.0, 62.0, 0.0],
                [768.964220631055, 183.0000007474319, 3.267289196301273e-06],
            ),
            (
                52521.25,
                [
                    2.844492633827471,
                    0.1262429153207661,
                    5.503758928358313,
                    -0.3861015108364216,
                    400.0,
                ],
                0.0,
                [
                    250.0, 200.0, 240.0, 200.0, 230.0, 200.0, 220.0, 195.0, 320.0,
                ],
                [1532.4960964996164, 1499.295346529408, 1.178190053211753e-11],
            ),
            (
                55168.75,
                [
                    4.366535718823735,
                    -0.3872526128441801,
                    4.391341768095334,
                    -0.9002672552884962,
                    1500.0,
                ],
                0.0,
                [70.0, 72.0, 60.0, 62.0, 65.0, 68.0, 60.0, 62.0, 320.0],
                [
                    1090.8949806649357,
                    1090.8651148956696,
                    1.2819695405819398e-15,
                ],
            ),
        ];
        for (amjd, g, _, ix, want) in cases {
            let out = jb2008(
                amjd,
                g[0],
                g[1],
                g[2],
                g[3],
                g[4],
                &Jb2008Indices::from_array(ix),
            )
            .unwrap();
            assert!(rel(out.tinf, want[0]) < 1e-9, "{out:?}");
            assert!(rel(out.temp, want[1]) < 1e-9, "{out:?}");
            assert!(rel(out.rho, want[2]) < 1e-6, "{out:?} vs {want:?}");
        }
    }

    #[test]
    fn bad_input_names_the_argument() {
        let ix = quiet();
        let e = jb2008(5e4, 0.0, 0.0, 0.0, 0.0, 89.0, &ix).unwrap_err();
        assert!(e.to_string().contains("altitude"), "{e}");
        let e = jb2008(5e4, 0.0, 0.0, 0.0, 1.6, 400.0, &ix).unwrap_err();
        assert!(e.to_string().contains("latitude"), "{e}");
        let e = jb2008(f64::NAN, 0.0, 0.0, 0.0, 0.0, 400.0, &ix).unwrap_err();
        assert!(e.to_string().contains("amjd"), "{e}");
        let e = density_geodetic(5e4, 91.0, 0.0, 4e5, &ix).unwrap_err();
        assert!(e.to_string().contains("latitude"), "{e}");
        let e = density_geodetic(5e4, 0.0, f64::INFINITY, 4e5, &ix).unwrap_err();
        assert!(e.to_string().contains("longitude"), "{e}");
        let mut bad = ix;
        bad.s10 = f64::NAN;
        let e = jb2008(5e4, 0.0, 0.0, 0.0, 0.0, 400.0, &bad).unwrap_err();
        assert!(e.to_string().contains("S10"), "{e}");
    }

    #[test]
    fn density_falls_with_altitude_and_rises_with_activity() {
        let ix = quiet();
        let mut last = f64::INFINITY;
        for k in 0..60 {
            let z = 90.0 + 40.0 * k as f64;
            let rho = jb2008(55000.3, 1.0, 0.2, 2.0, 0.3, z, &ix).unwrap().rho;
            assert!(rho.is_finite() && rho > 0.0 && rho < last, "{z} {rho}");
            last = rho;
        }
        let mut storm = ix;
        storm.dstdtc = 200.0;
        let a = jb2008(55000.3, 1.0, 0.2, 2.0, 0.3, 400.0, &ix).unwrap().rho;
        let b = jb2008(55000.3, 1.0, 0.2, 2.0, 0.3, 400.0, &storm)
            .unwrap()
            .rho;
        assert!(b > 1.5 * a);
    }

    #[test]
    fn reference_driver_geometry() {
        // The grid file's header prints the Sun position 2.0129, 0.3734 rad for
        // 2017-196 19:06:19.5 UTC (D1950 = 24668.79606).
        let d1950 = 24472.0 + 196.0 + (19.0 * 3600.0 + 6.0 * 60.0 + 19.5) / 86400.0;
        let (ra, dec) = sun_position(d1950 + MJD_1950);
        assert!((ra - 2.0129).abs() < 6e-5 && (dec - 0.3734).abs() < 6e-5);
        let th = greenwich_angle(d1950);
        assert!((0.0..std::f64::consts::TAU).contains(&th));
        // Day of year: 1.0 at Jan 1 00:00 (D1950 of 2017 Jan 1 = 24473).
        assert_eq!(day_of_year(24473.0), 1.0);
        assert!((day_of_year(24473.0 + 195.5) - 196.5).abs() < 1e-9);
    }
}
