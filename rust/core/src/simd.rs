//! SIMD batch width and runtime dispatch. Batch code is written once, generic over the
//! lane count `W` with plain lane loops; [`dispatch_on`] compiles it once more per
//! instruction set (AVX-512F, AVX2 + FMA) and runs the copy the CPU supports, so the wheel
//! stays portable and the wide kernels run (and are tested) on any machine.
//!
//! A batch is wider than a register: the right-hand side is a chain of square roots,
//! divisions and polynomials that each stage waits on, so one register's worth of members
//! leaves the vector units idle while the chain completes; 32 members (four AVX-512
//! registers, eight AVX2 ones per value) keep enough independent work in flight. Measured
//! on one thread, 64 members x 1 day (`cargo bench -p rhoprop-core --bench core -- '1
//! thread'`), exponential / field: AVX-512 8 lanes 4.55 / 7.89 ms, 16 lanes 2.42 / 5.34,
//! 32 lanes 2.13 / 4.80; AVX2 8 lanes 3.91 / 9.14, 16 3.37 / 7.57, 32 3.07 / 7.15.
//! [`batch_width`] picks the width per run.
//!
use std::sync::OnceLock;

/// Batch widths of the Monte Carlo engine, widest first.
pub const BATCH_WIDTHS: [usize; 3] = [32, 16, 8];

/// Members per batch for a run of `members` on `threads` worker threads: the widest of
/// [`BATCH_WIDTHS`] that still gives every thread a batch (a wider batch is cheaper per
/// member, an idle thread costs more), at least the narrowest. Results do not depend on
/// it: lanes never mix.
pub fn batch_width(members: usize, threads: usize) -> usize {
    let narrowest = BATCH_WIDTHS[BATCH_WIDTHS.len() - 1];
    BATCH_WIDTHS
        .into_iter()
        .find(|&w| members.div_ceil(w) >= threads.max(1))
        .unwrap_or(narrowest)
}

/// The instruction set batch kernels run with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimdPath {
    /// x86-64 with AVX-512F/DQ/VL (8 f64 lanes), AVX2 and FMA.
    Avx512,
    /// x86-64 with AVX2 and FMA.
    Avx2Fma,
    /// The baseline build of the target.
    Portable,
}

impl SimdPath {
    /// The path batch kernels take: the best the CPU offers, or the slower one
    /// `RHOPROP_SIMD` asks for. Detected once and cached.
    pub fn detect() -> Self {
        static PATH: OnceLock<SimdPath> = OnceLock::new();
        *PATH.get_or_init(|| {
            let best = Self::best();
            match std::env::var("RHOPROP_SIMD").as_deref() {
                Ok("portable") => SimdPath::Portable,
                Ok("avx2") if best != SimdPath::Portable => SimdPath::Avx2Fma,
                _ => best,
            }
        })
    }

    /// The widest path this CPU supports.
    pub fn best() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            if has!("avx2") && has!("fma") {
                return if has!("avx512f") && has!("avx512dq") && has!("avx512vl") {
                    SimdPath::Avx512
                } else {
                    SimdPath::Avx2Fma
                };
            }
        }
        SimdPath::Portable
    }

    /// Every path this CPU can run, widest first.
    pub fn available() -> Vec<Self> {
        [SimdPath::Avx512, SimdPath::Avx2Fma, SimdPath::Portable]
            .into_iter()
            .filter(|&p| p.rank() <= Self::best().rank())
            .collect()
    }

    fn rank(self) -> u8 {
        match self {
            SimdPath::Avx512 => 2,
            SimdPath::Avx2Fma => 1,
            SimdPath::Portable => 0,
        }
    }

    /// Short name for logs and benchmarks.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Avx512 => "avx512f",
            SimdPath::Avx2Fma => "avx2+fma",
            SimdPath::Portable => "portable",
        }
    }
}

/// A value that starts a cache line: batch states whose lane arrays vector loads read (a
/// load that splits a cache line costs extra; see [`crate::dynamics::Dynamics`]).
#[repr(C, align(64))]
pub struct Aligned<T>(pub T);

/// A unit of batch work that [`dispatch`] compiles once per instruction set. Implementors
/// mark `run` `#[inline(always)]` so that it, and everything it inlines (steps, RHS, stage
/// arithmetic), is generated inside each target-feature wrapper.
pub trait Kernel {
    type Output;
    fn run(self) -> Self::Output;
}

/// Runs `kernel` on the path [`SimdPath::detect`] chose.
#[inline]
pub fn dispatch<K: Kernel>(kernel: K) -> K::Output {
    dispatch_on(SimdPath::detect(), kernel)
}

/// Runs `kernel` compiled for `path`, which must be one of [`SimdPath::available`]
/// (others run the portable copy).
#[inline]
pub fn dispatch_on<K: Kernel>(path: SimdPath, kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    {
        if path.rank() <= SimdPath::best().rank() {
            match path {
                // SAFETY: the CPU supports each path's features (checked just above).
                SimdPath::Avx512 => return unsafe { run_avx512(kernel) },
                SimdPath::Avx2Fma => return unsafe { run_avx2_fma(kernel) },
                SimdPath::Portable => {}
            }
        }
    }
    kernel.run()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2,fma")]
unsafe fn run_avx512<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn run_avx2_fma<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sum([f64; 4]);
    impl Kernel for Sum {
        type Output = f64;
        #[inline(always)]
        fn run(self) -> f64 {
            self.0.iter().map(|x| x * 3.0 + 1.0).sum()
        }
    }

    #[test]
    fn batch_width_fills_the_threads() {
        assert_eq!(batch_width(1000, 2), 32);
        assert_eq!(batch_width(1000, 40), 16);
        assert_eq!(batch_width(1000, 64), 8);
        assert_eq!(batch_width(11, 1), 32);
        assert_eq!(batch_width(11, 2), 8);
        assert_eq!(batch_width(5, 8), 8);
        assert_eq!(batch_width(100, 0), 32);
    }

    #[test]
    fn every_path_matches_the_portable_one() {
        let k = || Sum([0.1, 0.2, 0.3, 0.4]);
        for path in SimdPath::available() {
            assert_eq!(dispatch_on(path, k()).to_bits(), k().run().to_bits());
        }
        assert!(SimdPath::available().contains(&SimdPath::detect()));
    }
}
