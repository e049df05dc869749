//! Which arithmetic traces a prism. A surface stored in `T` may trace a prism in `f64`
//! from its own data, widened exactly (the prism, the ray and the nonlinear ray in the exact
//! frame of [`nlrt_shellmap::in_f64`]), and round the hit back: the displacement-mapped
//! surface where Eq. 6 is ill-conditioned for the ray, the shell-mapped one always (see
//! `DisplacedSurface::intersect_blas` and `ShellSurface::intersect_blas`).

use nlrt_poly::Real;
use nlrt_shellmap::{NonlinearRay, Prism};

use crate::leaving::Exclusion;
use crate::stats::TraversalStats;

/// Which search a surface runs over one base triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Search {
    /// The BLAS walk.
    Walk,
    /// Every cell (texel or tile) of the triangle's uv box: the test reference.
    EveryCell,
}

/// A surface whose search over one base triangle runs in any precision.
pub(crate) trait PrismSearch<T: Real> {
    /// The hit of a search in `C`.
    type Hit<C: Real>;

    /// `search` over base triangle `tri`, computed in `C`; hits on the element `excluded`
    /// (the one a ray leaves, `crate::leaving`) are not taken.
    #[allow(clippy::too_many_arguments)]
    fn search_in<C: Real>(
        &self,
        search: Search,
        excluded: Option<Exclusion>,
        tri: usize,
        prism: &Prism<C>,
        ray: &NonlinearRay<C>,
        t_min: C,
        t_max: C,
        stats: &mut TraversalStats,
    ) -> Option<Self::Hit<C>>;

    /// A hit of an `f64` search, its values rounded to `T` (a distance within `[t_min,
    /// t_max]` of `T` stays there: rounding is monotonic).
    fn narrowed(hit: Self::Hit<f64>) -> Self::Hit<T>;

    /// `search` over base triangle `tri` in `f64` where `in_f64` (counted in
    /// [`TraversalStats::f64_prisms`]), else in `T`.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        in_f64: bool,
        search: Search,
        excluded: Option<Exclusion>,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<Self::Hit<T>> {
        let in_f64_whole = |stats: &mut TraversalStats| {
            stats.f64_prisms += 1;
            let (prism, ray) = nlrt_shellmap::in_f64(prism, &ray.ray);
            let (t_min, t_max) = (t_min.to_f64(), t_max.to_f64());
            self.search_in(search, excluded, tri, &prism, &ray, t_min, t_max, stats)
                .map(Self::narrowed)
        };
        if in_f64 {
            return in_f64_whole(stats);
        }
        let undecided = stats.undecided_in_f32;
        let hit = self.search_in(search, excluded, tri, prism, ray, t_min, t_max, stats);
        // A decision the walk could not make in `T` (`TraversalStats::undecided_in_f32`): the
        // prism is traced again in `f64`, whole, so that it is decided in one arithmetic
        // (dropping the one hit `f64` disowns instead leaked where the two arithmetics'
        // pieces differ: 5 f32 leaks of the paper-size torus at 1M rays). The every-cell
        // search, the tests' reference in the walk's arithmetic, stays in `T`.
        if matches!(search, Search::Walk) && stats.undecided_in_f32 != undecided {
            return in_f64_whole(stats);
        }
        hit
    }
}
