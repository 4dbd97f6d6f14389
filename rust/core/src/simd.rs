//! SIMD lane width and runtime dispatch. Batch code is written once, generic over the lane
//! count `W` with plain lane loops; [`dispatch_on`] compiles it once more per instruction
//! set (AVX-512F, AVX2 + FMA) and runs the copy the CPU supports, so the wheel stays
//! portable and the 8-lane kernels run (and are tested) on any machine. Both x86 paths
//! run batches of 8: one 8-wide register per operation on AVX-512, two 4-wide ones on
//! AVX2, whose independent halves hide the latency of the right-hand side's serial
//! square roots and divisions (8 lanes on AVX2 measured 8 % faster than 4 with the
//! exponential atmosphere and 6 % with a field; the portable build keeps 4, where 8 was
//! 5-20 % slower).
//!
//! Results are bit-identical on every path: Rust never contracts a * b + c into an FMA on
//! its own and lanes never mix, so the instruction set changes speed only. The
//! environment variable `RHOPROP_SIMD` (`avx512`, `avx2`, `portable`) picks a slower path
//! than the best one, for benchmarks and tests; a path the CPU lacks is ignored.

use std::sync::OnceLock;

/// Members (or sigma points) per batch on the portable path.
pub const LANES: usize = 4;

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

    /// Members per batch on this path.
    pub fn lanes(self) -> usize {
        match self {
            SimdPath::Avx512 | SimdPath::Avx2Fma => 8,
            SimdPath::Portable => LANES,
        }
    }

    /// Short name for logs and benchmarks.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Avx512 => "avx512f (8 lanes)",
            SimdPath::Avx2Fma => "avx2+fma (8 lanes)",
            SimdPath::Portable => "portable (4 lanes)",
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

    struct Sum([f64; LANES]);
    impl Kernel for Sum {
        type Output = f64;
        #[inline(always)]
        fn run(self) -> f64 {
            self.0.iter().map(|x| x * 3.0 + 1.0).sum()
        }
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
