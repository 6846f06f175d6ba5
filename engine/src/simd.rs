//! Clearing the upper halves of the vector registers after foreign AVX code.
//!
//! tract's AVX-512 kernels and Mesa's JIT-compiled shaders (lavapipe) may return with the
//! upper halves of the YMM/ZMM registers in use. The SSE code that follows (this crate is
//! compiled for the x86-64 baseline) then runs slower: on the project's 2-core machine (AMD
//! EPYC) the preprocessing of a `pilotnet` frame took 180 µs after a render and an inference,
//! 55 µs alone and 60 µs with this call (docs/performance.md, "The camera loop").
//! `vzeroupper` after such calls ends the slowdown; it changes no value this crate computes.

/// Issues `vzeroupper` where the CPU has AVX; does nothing elsewhere.
#[inline]
pub(crate) fn clear_upper_vector_state() {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the instruction exists on this CPU (checked above); it only zeroes the
            // upper halves of vector registers, which no live Rust value occupies across
            // this call.
            unsafe { zero_upper() }
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn zero_upper() {
    std::arch::x86_64::_mm256_zeroupper();
}
