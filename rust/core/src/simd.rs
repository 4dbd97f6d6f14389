//! SIMD lane width and runtime dispatch. Batch code is written once, generic over the lane
//! count `W` with plain lane loops; [`dispatch`] compiles it a second time for AVX2 + FMA
//! and picks that copy when the CPU has it, so the wheel stays portable. A wider path
//! (e.g. 8 lanes on AVX-512) only adds a variant and a target-feature wrapper here.
//!
//! Results are bit-identical on every path: Rust never contracts a * b + c into an FMA on
//! its own, so the instruction set changes speed only.

use std::sync::OnceLock;

/// Members (or sigma points) per batch, one per SIMD lane.
pub const LANES: usize = 4;

/// The instruction set batch kernels run with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimdPath {
    /// x86-64 with AVX2 and FMA.
    Avx2Fma,
    /// The baseline build of the target.
    Portable,
}

impl SimdPath {
    /// The path of this CPU, detected once and cached.
    pub fn detect() -> Self {
        static PATH: OnceLock<SimdPath> = OnceLock::new();
        *PATH.get_or_init(|| {
            #[cfg(target_arch = "x86_64")]
            {
                if std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
                {
                    return SimdPath::Avx2Fma;
                }
            }
            SimdPath::Portable
        })
    }

    /// Short name for logs and benchmarks.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Avx2Fma => "avx2+fma",
            SimdPath::Portable => "portable",
        }
    }
}

/// A unit of batch work that [`dispatch`] compiles once per instruction set. Implementors
/// mark `run` `#[inline(always)]` so that it, and everything it inlines (steps, RHS, stage
/// arithmetic), is generated inside each target-feature wrapper.
pub trait Kernel {
    type Output;
    fn run(self) -> Self::Output;
}

/// Runs `kernel` with the widest instruction set the CPU offers.
#[inline]
pub fn dispatch<K: Kernel>(kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    {
        if SimdPath::detect() == SimdPath::Avx2Fma {
            // SAFETY: the CPU supports AVX2 and FMA (detected above).
            return unsafe { run_avx2_fma(kernel) };
        }
    }
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
    fn dispatch_matches_the_portable_path() {
        let k = || Sum([0.1, 0.2, 0.3, 0.4]);
        assert_eq!(dispatch(k()).to_bits(), k().run().to_bits());
        assert!(["avx2+fma", "portable"].contains(&SimdPath::detect().name()));
    }
}
