//! Counters of a traversal, kept by every walk (cheap enough to leave on).

/// Counters of one traversal (for reports; cheap enough to keep on).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Prisms whose exact test ran.
    pub prism_tests: u32,
    /// Texture-space box tests.
    pub box_tests: u32,
    /// Texels tested (each one or two microtriangles, or one flat rectangle).
    pub texel_tests: u32,
    /// Base triangles whose walk along the ray's curve outgrew its fixed stack and was
    /// finished by box tests (slower, same answer).
    pub fallbacks: u32,
    /// Prisms of an `f32` surface traced in `f64`, where Eq. 6 is ill-conditioned for the ray
    /// (`DisplacedSurface::intersect_blas`), or where `f32` met a decision it could not make.
    pub f64_prisms: u32,
    /// Texel decisions an `f32` walk could not make that `f64` makes otherwise (near a pole of
    /// the ray's curve: the signs at a split point, or a root the cubic's signs cannot vouch
    /// for); each sends its prism to `f64`, whole.
    pub undecided_in_f32: u32,
}
