//! Helpers shared by the crate's unit tests.

/// Knuth's MMIX linear congruential generator from `seed`: uniform numbers in `[0, 1)` from
/// the state's top 53 bits (deterministic test inputs, no dependency).
pub(crate) fn unit_randoms(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A direction component in `[-1, 1)` from `r` (uniform in `[0, 1)`), one in five scaled by
/// `1e-9`: rays and lines nearly parallel to an axis, whose reciprocal directions are huge.
pub(crate) fn direction_component(r: &mut impl FnMut() -> f64) -> f64 {
    let m = (r() - 0.5) * 2.0;
    if r() < 0.2 { m * 1e-9 } else { m }
}
