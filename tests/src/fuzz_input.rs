//! Decoding of fuzz inputs and the properties every solver answer must have. The cargo-fuzz
//! targets in `fuzz/` and the replay test `tests/fuzz_replay.rs` both call these, so what the
//! fuzzer checks and what CI replays are the same code.
//!
//! An input is read as raw IEEE bit patterns: `N` coefficients (ascending powers), then the
//! interval ends `lo` and `hi`. Missing bytes read as zero; when fewer than `N + 2` values are
//! present the interval is the whole line. Every bit pattern is possible: NaN, infinities,
//! subnormals, signed zeros.

use nlrt_poly::{
    CUBIC_BATCH, QUADRATIC_BATCH, Real, first_cubic_root_batch_in, first_cubic_root_in,
    horner_with_bound_scaled, solve_cubic_batch_in, solve_cubic_in, solve_quadratic_batch_in,
    solve_quadratic_in,
};

/// What the decoder made of the bytes.
#[derive(Clone, Copy, Debug)]
pub struct Input<T: Real, const N: usize> {
    /// Coefficients, ascending powers.
    pub coeffs: [T; N],
    /// Interval start.
    pub lo: T,
    /// Interval end.
    pub hi: T,
}

/// Reads `N` coefficients and two interval ends from raw bytes (see the module docs).
#[must_use]
pub fn decode<T: Real, const N: usize>(data: &[u8]) -> Input<T, N> {
    let width = (T::BITS / 8) as usize;
    let value = |i: usize| {
        let mut bits = 0u64;
        for k in 0..width {
            let byte = data.get(i * width + k).copied().unwrap_or(0);
            bits |= u64::from(byte) << (8 * k);
        }
        T::from_bits_u64(bits)
    };
    let coeffs = core::array::from_fn(value);
    let (lo, hi) = if data.len() >= (N + 2) * width {
        (value(N), value(N + 1))
    } else {
        (T::NEG_INFINITY, T::INFINITY)
    };
    Input { coeffs, lo, hi }
}

/// Encodes an input the way [`decode`] reads it (for writing seed files).
#[must_use]
pub fn encode<T: Real, const N: usize>(input: &Input<T, N>) -> Vec<u8> {
    let width = (T::BITS / 8) as usize;
    let mut out = Vec::new();
    for v in input.coeffs.iter().chain([&input.lo, &input.hi]) {
        out.extend_from_slice(&v.to_bits_u64().to_le_bytes()[..width]);
    }
    out
}

/// How far above the evaluation's own error bound a reported root's residual may be: a root
/// within a few ulps of a true root has `|p(x)| <= |p'| |dx| <= 3 sum|c_i||x|^i * 2u * ulps`,
/// about `ulps` times the bound of `horner_with_bound` (which is `2 n u sum|c_i||x|^i`), plus the
/// bound once more for the rounding of the check itself.
pub const RESIDUAL_FACTOR: f64 = 5.0;

/// Checks the properties of one answer; panics with a description on violation.
///
/// - Non-finite coefficients or a NaN/empty interval: no roots (the documented result).
/// - Otherwise: roots finite, strictly increasing, inside `[lo, hi]`, and each either with a
///   residual `|p(x)| <= RESIDUAL_FACTOR * bound(x)` or within one ulp of a sign change of `p`
///   (a root whose neighbouring floats are far apart relative to it, e.g. one that underflows,
///   cannot have a small residual at any float).
pub fn check_answer<T: Real, const N: usize>(input: &Input<T, N>, roots: &[T]) {
    let Input { coeffs, lo, hi } = *input;
    let finite = coeffs.iter().all(|c| c.is_finite());
    if !(finite && lo <= hi) {
        assert!(
            roots.is_empty(),
            "bad input must give no roots: {input:?} -> {roots:?}"
        );
        return;
    }
    for w in roots.windows(2) {
        assert!(
            w[0] < w[1],
            "roots not strictly increasing: {input:?} -> {roots:?}"
        );
    }
    for &x in roots {
        assert!(x.is_finite(), "non-finite root: {input:?} -> {roots:?}");
        assert!(
            x >= lo && x <= hi,
            "root {x:e} outside [{lo:e}, {hi:e}]: {input:?} -> {roots:?}"
        );
        let (v, bound) = residual(&coeffs, x);
        assert!(
            v <= bound * RESIDUAL_FACTOR || sign_changes_around(&coeffs, x),
            "residual {v:e} above {RESIDUAL_FACTOR} x bound {bound:e} at {x:e}, and no sign change within one ulp: \
             {input:?} -> {roots:?}"
        );
    }
}

/// Whether `p` changes sign (or is within rounding of zero) between the floats next to `x`.
fn sign_changes_around<T: Real, const N: usize>(coeffs: &[T; N], x: T) -> bool {
    let c: [f64; N] = coeffs.map(Real::to_f64);
    let sign = |y: T| {
        let (v, b) = horner_with_bound_scaled(&c, y.to_f64());
        if v.abs() <= b {
            0
        } else if v > 0.0 {
            1
        } else {
            -1
        }
    };
    let (below, above) = (sign(x.next_down()), sign(x.next_up()));
    below == 0 || above == 0 || below != above
}

/// `|p(x)|` and its rounding bound, evaluated in f64 with local normalization (so neither
/// overflows nor sinks into subnormals; both carry the same power-of-two factor). For f32
/// inputs the bound is scaled up to f32's unit roundoff: the noise the solver worked with.
fn residual<T: Real, const N: usize>(coeffs: &[T; N], x: T) -> (f64, f64) {
    let c: [f64; N] = coeffs.map(Real::to_f64);
    let (v, bound) = horner_with_bound_scaled(&c, x.to_f64());
    let scale = T::UNIT_ROUNDOFF.to_f64() / f64::UNIT_ROUNDOFF;
    (v.abs(), bound * scale.max(1.0))
}

/// The cubic fuzz target: decode, solve, check; also checks that the nearest-root call agrees.
pub fn fuzz_cubic<T: Real>(data: &[u8]) {
    let input = decode::<T, 4>(data);
    let roots = solve_cubic_in(input.coeffs, input.lo, input.hi);
    check_answer(&input, &roots);
    let first = first_cubic_root_in(input.coeffs, input.lo, input.hi);
    assert_eq!(
        first,
        roots.first().copied(),
        "first root differs from all roots: {input:?}"
    );
}

/// Bytes per input of [`fuzz_cubic_batch`]: four coefficients and two interval ends.
#[must_use]
pub fn cubic_input_bytes<T: Real>() -> usize {
    6 * (T::BITS / 8) as usize
}

/// The batch cubic fuzz target: [`CUBIC_BATCH`] inputs of [`cubic_input_bytes`] each, every
/// one decoded as [`fuzz_cubic`] decodes its input (missing bytes read as zero, a short input
/// is solved on the whole line). The batch answers must be the scalar answers bit for bit, and
/// the scalar answers must pass [`check_answer`].
pub fn fuzz_cubic_batch<T: Real>(data: &[u8]) {
    let width = cubic_input_bytes::<T>();
    let inputs: [Input<T, 4>; CUBIC_BATCH] = core::array::from_fn(|i| {
        let start = (i * width).min(data.len());
        let end = ((i + 1) * width).min(data.len());
        decode::<T, 4>(&data[start..end])
    });
    let c = inputs.map(|x| x.coeffs);
    let (lo, hi) = (inputs.map(|x| x.lo), inputs.map(|x| x.hi));
    let all = solve_cubic_batch_in(&c, &lo, &hi);
    let first = first_cubic_root_batch_in(&c, &lo, &hi);
    for (i, input) in inputs.iter().enumerate() {
        let scalar = solve_cubic_in(input.coeffs, input.lo, input.hi);
        assert_eq!(
            bits(&all[i]),
            bits(&scalar),
            "batch lane {i} differs from the scalar solver: {input:?}"
        );
        check_answer(input, &scalar);
        let scalar_first = first_cubic_root_in(input.coeffs, input.lo, input.hi);
        assert_eq!(
            bits(first[i].as_slice()),
            bits(scalar_first.as_slice()),
            "batch first root of lane {i} differs from the scalar solver: {input:?}"
        );
    }
}

/// The bit patterns of roots, for comparing answers exactly (signed zeros included).
fn bits<T: Real>(roots: &[T]) -> Vec<u64> {
    roots.iter().map(|v| v.to_bits_u64()).collect()
}

/// The quadratic fuzz target: decode, solve, check; and the batch solver on eight inputs,
/// lane `i` decoded from the bytes after the first `i` values (lane 0 is the checked input),
/// which must give the scalar answers bit for bit.
pub fn fuzz_quadratic<T: Real>(data: &[u8]) {
    let input = decode::<T, 3>(data);
    let roots = solve_quadratic_in(input.coeffs, input.lo, input.hi);
    check_answer(&input, &roots);
    let width = (T::BITS / 8) as usize;
    let lanes: [Input<T, 3>; QUADRATIC_BATCH] =
        core::array::from_fn(|i| decode::<T, 3>(&data[(i * width).min(data.len())..]));
    let c: [[T; QUADRATIC_BATCH]; 3] = core::array::from_fn(|k| lanes.map(|x| x.coeffs[k]));
    let batch = solve_quadratic_batch_in(&c, &lanes.map(|x| x.lo), &lanes.map(|x| x.hi));
    for (i, lane) in lanes.iter().enumerate() {
        let scalar = solve_quadratic_in(lane.coeffs, lane.lo, lane.hi);
        assert_eq!(
            bits(&batch[i]),
            bits(&scalar),
            "batch lane {i} differs from the scalar solver: {lane:?}"
        );
    }
}

/// The microtriangle fuzz target: a prism (base, normals, uvs), a ray, a texture-space
/// triangle and a height range, all raw bit patterns. No panic; a reported hit is finite, has
/// `t` and `h` in their ranges and `(alpha, beta)` in the base triangle; the nonlinear ray's
/// coefficients are computed without panicking for any input.
pub fn fuzz_microtriangle<T: Real>(data: &[u8]) {
    use nlrt_poly::{Vector2, Vector3};
    use nlrt_shellmap::{NonlinearRay, Prism, Ray, intersect_microtriangle};
    let x = decode::<T, 38>(data).coeffs;
    let v3 = |i: usize| T::Vec3::new(x[i], x[i + 1], x[i + 2]);
    let prism = Prism::<T>::new(
        [v3(0), v3(3), v3(6)],
        [v3(9), v3(12), v3(15)],
        [
            T::Vec2::new(x[18], x[19]),
            T::Vec2::new(x[20], x[21]),
            T::Vec2::new(x[22], x[23]),
        ],
    );
    let Some(ray) = Ray::new(v3(24), v3(27)) else {
        return;
    };
    let tri = [v3(30), v3(33), T::Vec3::new(x[36], x[37], x[30])];
    let nl = NonlinearRay::new(&prism, &ray);
    let (h_lo, h_hi) = (T::ZERO, T::ONE);
    if let Some(hit) = intersect_microtriangle(&prism, &nl, &tri, h_lo, h_hi, T::ZERO, T::INFINITY)
    {
        let all = [hit.t, hit.alpha, hit.beta, hit.h, hit.u, hit.v];
        assert!(all.iter().all(|v| v.is_finite()), "non-finite hit {hit:?}");
        assert!(
            hit.t >= T::ZERO && hit.h >= h_lo && hit.h <= h_hi,
            "hit out of range {hit:?}"
        );
        assert!(
            hit.alpha >= T::ZERO && hit.beta >= T::ZERO && hit.alpha + hit.beta <= T::ONE,
            "hit outside the prism {hit:?}"
        );
    }
}

/// Layout shared by the traversal targets: a header byte for the map or object, then raw
/// values for one base triangle (positions, normals, uvs: 24 values) and a ray (6 values).
fn base_and_ray<T: Real>(x: &[T]) -> Option<(nlrt_accel::BaseMesh<T>, nlrt_shellmap::Ray<T>)> {
    use nlrt_poly::{Vector2, Vector3};
    let v3 = |i: usize| T::Vec3::new(x[i], x[i + 1], x[i + 2]);
    let mesh = nlrt_accel::BaseMesh::new(
        vec![v3(0), v3(3), v3(6)],
        vec![v3(9), v3(12), v3(15)],
        vec![
            T::Vec2::new(x[18], x[19]),
            T::Vec2::new(x[20], x[21]),
            T::Vec2::new(x[22], x[23]),
        ],
        vec![[0, 1, 2]],
    )
    .ok()?;
    let ray = nlrt_shellmap::Ray::new(v3(24), v3(27))?;
    Some((mesh, ray))
}

/// What every hit of a traversal must be: finite, `t >= 0`, `h` in `[0, 1]`, `(alpha, beta)`
/// in the base triangle (`context` is printed on failure).
fn check_traversal_hit<T: Real>(h: &nlrt_shellmap::Hit<T>, context: &dyn core::fmt::Debug) {
    assert!(
        [h.t, h.alpha, h.beta, h.h, h.u, h.v]
            .iter()
            .all(|v| v.is_finite()),
        "non-finite hit {context:?}"
    );
    assert!(
        h.t >= T::ZERO && h.h >= T::ZERO && h.h <= T::ONE,
        "hit out of range {context:?}"
    );
    assert!(
        h.alpha >= T::ZERO && h.beta >= T::ZERO && h.alpha + h.beta <= T::ONE,
        "hit outside the prism {context:?}"
    );
}

/// Texel (or tile) ranges up to this many cells are also tested by brute force.
const BRUTE_FORCE_CELLS: i64 = 4096;

/// The height map that leads a traversal input: a header byte (side 2 to 16, wrap mode,
/// tiling 1 to 4, and with `any_size` its top three bits making the map narrower by up to three
/// samples and, with the top bit, about half as high: sizes that are neither square nor powers
/// of two; 0 there keeps the square map, which every older unit of the displacement target
/// has), then the samples as little-endian 16-bit values (missing bytes read as 0); with the
/// bytes after them.
fn map_of<T: Real>(data: &[u8], any_size: bool) -> (nlrt_accel::HeightField, T, &[u8]) {
    use nlrt_accel::{HeightField, Wrap};
    let header = data.first().copied().unwrap_or(0);
    let side = 2usize << (header & 3);
    let (width, height) = if any_size {
        let narrower = usize::from((header >> 5) & 3);
        let lower = header & 0x80 != 0;
        (
            side.saturating_sub(narrower).max(2),
            if lower { side / 2 + 1 } else { side },
        )
    } else {
        (side, side)
    };
    let wrap = if header & 4 == 0 {
        Wrap::Repeat
    } else {
        Wrap::Clamp
    };
    let tiling = T::from_i32(i32::from((header >> 3) & 3) + 1);
    let sample_bytes = data.get(1..).unwrap_or(&[]);
    let samples = (0..width * height)
        .map(|i| {
            let b = |k: usize| u16::from(sample_bytes.get(2 * i + k).copied().unwrap_or(0));
            b(0) | (b(1) << 8)
        })
        .collect();
    let field = HeightField::new(width, height, samples, wrap).expect("sides from 2 to 16");
    (
        field,
        tiling,
        data.get(1 + 2 * width * height..).unwrap_or(&[]),
    )
}

/// The surface and ray of a [`fuzz_displacement`] input, or why set-up rejects it.
///
/// # Errors
/// No valid base mesh and ray in the bytes, or the surface's own error message.
pub fn displacement_case<T: Real>(
    data: &[u8],
) -> Result<(nlrt_accel::DisplacedSurface<T>, nlrt_shellmap::Ray<T>), String> {
    use nlrt_accel::DisplacedSurface;
    let (mesh, field, tiling, ray) = displacement_parts::<T>(data)?;
    let surface = DisplacedSurface::new(mesh, field, T::ONE, tiling).map_err(|e| e.to_string())?;
    Ok((surface, ray))
}

/// [`displacement_case`] with the triangle made affine: its first direction at all three
/// corners, so that the straight walk takes it where its frame is well-conditioned.
///
/// # Errors
/// The bytes hold no valid base triangle and ray, or the affine triangle is refused.
pub fn affine_displacement_case<T: Real>(
    data: &[u8],
) -> Result<(nlrt_accel::DisplacedSurface<T>, nlrt_shellmap::Ray<T>), String> {
    let (mesh, field, tiling, ray) = displacement_parts::<T>(data)?;
    let flat = nlrt_accel::BaseMesh::new(
        mesh.positions().to_vec(),
        vec![mesh.normals()[0]; 3],
        mesh.uvs().to_vec(),
        vec![[0, 1, 2]],
    )
    .map_err(|e| e.to_string())?;
    let surface = nlrt_accel::DisplacedSurface::new(flat, field, T::ONE, tiling)
        .map_err(|e| e.to_string())?;
    Ok((surface, ray))
}

/// What [`displacement_case`] builds its surface from: the base mesh, the height map, the
/// tiling and the ray (a test may build the surface otherwise, with another tiling).
///
/// # Errors
/// The bytes hold no valid base triangle and ray.
pub fn displacement_parts<T: Real>(
    data: &[u8],
) -> Result<
    (
        nlrt_accel::BaseMesh<T>,
        nlrt_accel::HeightField,
        T,
        nlrt_shellmap::Ray<T>,
    ),
    String,
> {
    let (field, tiling, rest) = map_of::<T>(data, true);
    let x = decode::<T, 30>(rest).coeffs;
    let (mesh, ray) = base_and_ray(&x).ok_or("no valid base triangle and ray")?;
    Ok((mesh, field, tiling, ray))
}

/// Texels of a triangle's range up to which [`fuzz_displacement`] also traces the
/// tessellation-free baseline: its work grows with the area of that range where its world
/// boxes do not prune (`fuzz/slow/displacement_f32/affine-range-walk*`: up to 415M texel tests,
/// 55 s in release), which stopped every 600-second libFuzzer run of `displacement_f32` on a
/// slow input. 2^22 texels is about half a second in release (8.9M took 1.0 s), a few seconds
/// under ASan: the baseline is still checked on most inputs, and the fuzzer's time goes to the
/// nonlinear walks, whose cost follows the texels the ray crosses.
pub const AFFINE_BASELINE_CELLS: i64 = 1 << 22;

/// The displacement traversal target: a small height map (side 2 to 16, any samples, either
/// wrap mode, tiling 1 to 4), one base triangle and a ray, all from raw bytes. No panic; a hit
/// is finite, in `[0, inf)`, with `h` in `[0, 1]` and `(alpha, beta)` in the base triangle,
/// from the straight walk (the triangle as given where its three directions are equal, and
/// again with its first direction at every corner) and the curved one;
/// and the curved walk's hit is never nearer than the brute-force one (the traversal tests a
/// subset of the same texels with the same arithmetic), checked when the texel range is small;
/// the occlusion query agrees with the curved walk's nearest hit on whether there is one.
pub fn fuzz_displacement<T: Real>(data: &[u8]) {
    use nlrt_accel::TraversalStats;
    use nlrt_baselines::{AffineTracing, ConeTraced, Marching};
    let Ok((mut surface, ray)) = displacement_case::<T>(data) else {
        return;
    };
    if surface.straight_triangles() > 0 {
        let straight =
            surface.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default());
        if let Some(hit) = straight {
            check_traversal_hit(&hit.hit, &hit);
        }
    }
    // The same triangle with its first direction at all three corners: an affine prism,
    // walked along the straight line (where its frame is well-conditioned).
    if let Ok((affine, _)) = affine_displacement_case::<T>(data)
        && let Some(hit) =
            affine.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default())
    {
        check_traversal_hit(&hit.hit, &hit);
    }
    surface.set_straight_walk(false);
    let mut walk_stats = TraversalStats::default();
    let fast = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut walk_stats);
    if let Some(hit) = fast {
        check_traversal_hit(&hit.hit, &hit);
    }
    // The occlusion query asks the same prisms with the same range until one holds a hit.
    assert_eq!(
        surface.occluded(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default()),
        fast.is_some(),
        "occlusion query against {fast:?}"
    );
    // A ray leaving the hit back towards the ray's origin: no panic, any hit finite, ahead
    // and not the element it leaves, and the occlusion query agreeing with it.
    if let Some(hit) = fast
        && let Some(back) = nlrt_shellmap::Ray::new(ray.at(hit.hit.t), -ray.dir)
    {
        let stats = &mut TraversalStats::default();
        let left = surface.intersect_leaving(&back, &hit, hit.hit.t, stats);
        if let Some(l) = left {
            assert!(l.hit.t.is_finite() && l.hit.t >= T::ZERO, "leaving {l:?}");
            assert!(
                (l.triangle, l.texel, l.part) != (hit.triangle, hit.texel, hit.part),
                "leaving {hit:?} hit it again: {l:?}"
            );
        }
        assert_eq!(
            surface.occluded_leaving(&back, &hit, hit.hit.t, stats),
            left.is_some(),
            "leaving occlusion query against {left:?}"
        );
    }
    let [x0, y0, x1, y1] = surface.roots(0).texels.map(i64::from);
    // The brute force tests every texel in the walk's arithmetic: not comparable where the
    // walk met a decision `f32` could not make and traced the prism in `f64`.
    if (x1 - x0 + 1) * (y1 - y0 + 1) <= BRUTE_FORCE_CELLS
        && walk_stats.undecided_in_f32 == 0
        && let Some(f) = fast
    {
        let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
        let b = brute.expect("brute force tests every texel the traversal tests");
        assert!(
            f.hit.t >= b.hit.t,
            "accelerated {f:?} nearer than brute force {b:?}"
        );
    }
    // The competing methods on the same surface: no panic, and any hit finite and ahead.
    let mut stats = TraversalStats::default();
    if (x1 - x0 + 1) * (y1 - y0 + 1) <= AFFINE_BASELINE_CELLS
        && let Some(h) = surface.intersect_affine(&ray, T::ZERO, T::INFINITY, &mut stats)
    {
        assert!(h.t.is_finite() && h.t > T::ZERO, "tessellation-free {h:?}");
    }
    let opts = nlrt_baselines::MarchOptions {
        max_samples: 256,
        ..nlrt_baselines::MarchOptions::default()
    };
    if let Some(h) = surface.intersect_marching(&ray, T::ZERO, T::INFINITY, &opts, &mut stats) {
        assert!(h.hit.t.is_finite() && h.hit.t > T::ZERO, "marching {h:?}");
    }
    if let Some(h) =
        surface.intersect_curved_marching(&ray, T::ZERO, T::INFINITY, &opts, &mut stats)
    {
        assert!(h.hit.t.is_finite() && h.hit.t > T::ZERO, "curved {h:?}");
        let _ = surface.curved_normal(&h, ray.dir);
    }
    // Cone maps are built for square maps with a power-of-two side only.
    if surface.field().square_side().is_some() {
        let cone = nlrt_baselines::ConeTracing::new(
            &surface,
            nlrt_baselines::ConeOptions {
                max_steps: 256,
                ..nlrt_baselines::ConeOptions::default()
            },
        );
        if let Some(h) =
            surface.intersect_cone_traced(&ray, T::ZERO, T::INFINITY, &cone, &mut stats)
        {
            assert!(
                h.hit.t.is_finite() && h.hit.t > T::ZERO,
                "cone tracing {h:?}"
            );
        }
    }
}

/// Values a [`fuzz_seam`] input holds after its header and map: four positions (12), the
/// normals (18) and uvs (12) of the two triangles' own vertex copies, and a ray (6).
pub const SEAM_VALUES: usize = 48;

/// The surfaces of a [`fuzz_seam`] input: the two triangles `(p0, p1, p2)` and `(p0, p2, p3)`
/// on their own vertices (so the diagonal is a seam wherever their uvs or normals differ
/// there), closed by the seam rule and left open, and the ray; `None` where set-up rejects
/// the input.
#[must_use]
pub fn seam_case<T: Real>(
    data: &[u8],
) -> Option<(
    nlrt_accel::DisplacedSurface<T>,
    nlrt_accel::DisplacedSurface<T>,
    nlrt_shellmap::Ray<T>,
)> {
    use nlrt_accel::{BaseMesh, DisplacedSurface, SeamRule};
    use nlrt_poly::{Vector2, Vector3};
    let (field, tiling, rest) = map_of::<T>(data, false);
    let x = decode::<T, SEAM_VALUES>(rest).coeffs;
    let v3 = |i: usize| T::Vec3::new(x[i], x[i + 1], x[i + 2]);
    let p = [v3(0), v3(3), v3(6), v3(9)];
    let normals = (0..6).map(|k| v3(12 + 3 * k)).collect();
    let uvs = (0..6)
        .map(|k| T::Vec2::new(x[30 + 2 * k], x[31 + 2 * k]))
        .collect();
    let mesh = BaseMesh::new(
        vec![p[0], p[1], p[2], p[0], p[2], p[3]],
        normals,
        uvs,
        vec![[0, 1, 2], [3, 4, 5]],
    )
    .ok()?;
    let ray = nlrt_shellmap::Ray::new(v3(42), v3(45))?;
    let closed = DisplacedSurface::new(mesh.clone(), field.clone(), T::ONE, tiling).ok()?;
    let open =
        DisplacedSurface::with_seam_rule(mesh, field, T::ONE, tiling, SeamRule::Open).ok()?;
    Some((closed, open, ray))
}

/// Whether the two triangles of a [`seam_case`] surface lie on the same three positions.
fn same_corners<T: Real>(surface: &nlrt_accel::DisplacedSurface<T>) -> bool {
    use nlrt_poly::Vector3;
    let mesh = surface.mesh();
    let corners = |t: usize| {
        let mut c = mesh.triangle(t).map(|i| mesh.positions()[i as usize]);
        c.sort_by(|a, b| {
            (a.x(), a.y(), a.z())
                .partial_cmp(&(b.x(), b.y(), b.z()))
                .unwrap_or(core::cmp::Ordering::Equal)
        });
        c
    };
    corners(0) == corners(1)
}

/// The seam target: a small map, two triangles that share an edge's positions with any uvs
/// and normals on their own vertices, and a ray, from raw bytes. No panic under either seam
/// rule; every hit (seam walls included) finite, ahead, with `h` in `[0, 1]` and `(alpha,
/// beta)` in its base triangle (the straight walk's too, where the two triangles form an
/// affine patch); a seam wall only on a seam edge; and the curved walk's hit never nearer than
/// testing every texel and wall, checked when the texel ranges are small.
pub fn fuzz_seam<T: Real>(data: &[u8]) {
    use nlrt_accel::{NO_SEAM, TexelPart, TraversalStats};
    let Some((mut closed, mut open, ray)) = seam_case::<T>(data) else {
        return;
    };
    // One edge, or all three where the two triangles lie on the same three positions.
    let seam_edges = closed.seams().edges().len();
    assert!(
        seam_edges <= 1 || (seam_edges <= 3 && same_corners(&closed)),
        "two triangles share one edge, or all three when they coincide: {seam_edges}"
    );
    for surface in [&mut closed, &mut open] {
        // Two triangles with one direction and no seam form an affine patch, walked straight:
        // its hits are checked as every hit; the comparison with brute force (the same
        // arithmetic) is the curved walk's.
        if surface.straight_triangles() > 0
            && let Some(hit) =
                surface.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default())
        {
            check_traversal_hit(&hit.hit, &hit);
        }
        surface.set_straight_walk(false);
        let surface = &*surface;
        let fast = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default());
        let Some(hit) = fast else {
            continue;
        };
        check_traversal_hit(&hit.hit, &hit);
        if let TexelPart::Wall { edge } = hit.part {
            let walls = surface.seams().of_triangle(hit.triangle as usize);
            assert!(
                walls.is_some_and(|w| w[usize::from(edge)] != NO_SEAM),
                "a wall hit off a seam {hit:?}"
            );
            let _ = surface.normal(&hit, ray.dir);
        }
        let small = (0..2).all(|t| {
            let [x0, y0, x1, y1] = surface.roots(t).texels.map(i64::from);
            (x1 - x0 + 1) * (y1 - y0 + 1) <= BRUTE_FORCE_CELLS
        });
        if small {
            let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
            let b = brute.expect("brute force tests every texel and wall the traversal tests");
            assert!(
                hit.hit.t >= b.hit.t,
                "accelerated {hit:?} nearer than brute force {b:?}"
            );
        }
    }
}

/// A structured [`fuzz_seam`] input from `seed` (deterministic): a unit square whose two
/// triangles' copies of the diagonal's ends get other uvs and tilted normals (each at random,
/// so some inputs have a uv seam, some a normal seam, some both or none), a random map, and a
/// ray from above at a random angle, grazing ones included. For the seed corpus and for the
/// property test that runs many of them.
#[must_use]
pub fn seam_seed<T: Real>(seed: u64) -> Vec<u8> {
    let mut state = seed
        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
        .wrapping_add(0x2545_f491_4f6c_dd1d);
    let mut next = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let mut unit = || (next() >> 11) as f64 / (1u64 << 53) as f64;
    let header = (unit() * 256.0) as u8;
    let side = 2usize << (header & 3);
    let mut bytes = vec![header];
    for _ in 0..2 * side * side {
        bytes.push((unit() * 256.0) as u8);
    }
    let mut values: Vec<f64> = Vec::with_capacity(SEAM_VALUES);
    let corners = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for c in corners {
        values.extend([c[0], c[1], 0.2 * unit() - 0.1]);
    }
    let tilt = |u: &mut dyn FnMut() -> f64| [0.8 * u() - 0.4, 0.8 * u() - 0.4, 1.0];
    let (same_normals, same_uvs) = (unit() < 0.3, unit() < 0.3);
    let normal_a: Vec<[f64; 3]> = (0..3).map(|_| tilt(&mut unit)).collect();
    let normal_b: Vec<[f64; 3]> = (0..3).map(|_| tilt(&mut unit)).collect();
    // Copies: triangle A = (p0, p1, p2), B = (p0, p2, p3).
    let normals_b = if same_normals {
        [normal_a[0], normal_a[2], normal_b[2]]
    } else {
        [normal_b[0], normal_b[1], normal_b[2]]
    };
    for n in normal_a.iter().chain(normals_b.iter()) {
        values.extend(n);
    }
    let scale = 0.2 + 0.8 * unit();
    let shift_a = [unit(), unit()];
    let shift_b = if same_uvs { shift_a } else { [unit(), unit()] };
    for (k, c) in [0, 1, 2, 0, 2, 3].into_iter().enumerate() {
        let shift = if k < 3 { shift_a } else { shift_b };
        values.extend([
            corners[c][0] * scale + shift[0],
            corners[c][1] * scale + shift[1],
        ]);
    }
    let origin = [2.0 * unit() - 0.5, 2.0 * unit() - 0.5, 0.05 + 1.5 * unit()];
    let target = [unit(), unit(), 0.3 * unit()];
    values.extend(origin);
    values.extend((0..3).map(|i| target[i] - origin[i]));
    let width = (T::BITS / 8) as usize;
    for v in values {
        bytes.extend_from_slice(&T::from_f64(v).to_bits_u64().to_le_bytes()[..width]);
    }
    bytes
}

/// The surface and ray of a [`fuzz_shell`] input, or why set-up rejects it.
///
/// # Errors
/// No valid object, base mesh and ray in the bytes, or the surface's own error message.
pub fn shell_case<T: Real>(
    data: &[u8],
) -> Result<(nlrt_accel::ShellSurface<T>, nlrt_shellmap::Ray<T>), String> {
    shell_case_with::<T>(data, false)
}

/// [`shell_case`], or with `affine` its affine variant ([`affine_shell_case`]).
fn shell_case_with<T: Real>(
    data: &[u8],
    affine: bool,
) -> Result<(nlrt_accel::ShellSurface<T>, nlrt_shellmap::Ray<T>), String> {
    use nlrt_accel::{ShellObject, ShellSurface};
    use nlrt_poly::Vector3;
    let header = data.first().copied().unwrap_or(0);
    let count = usize::from(header & 3) + 1;
    let tiling = T::from_i32(i32::from((header >> 2) & 7) + 1);
    let x = decode::<T, 66>(data.get(1..).unwrap_or(&[])).coeffs;
    let unit = |v: T| {
        // Map raw values into [0, 1] mostly, but keep a few out-of-range ones (errors).
        if v.is_finite() && v.abs() <= T::from_i32(2) {
            v.abs() * T::HALF
        } else {
            v
        }
    };
    let object: Vec<[T::Vec3; 3]> = (0..count)
        .map(|t| {
            core::array::from_fn(|k| {
                let i = 30 + 9 * t + 3 * k;
                T::Vec3::new(unit(x[i]), unit(x[i + 1]), unit(x[i + 2]))
            })
        })
        .collect();
    let object = ShellObject::new(object).map_err(|e| e.to_string())?;
    let (mesh, ray) = base_and_ray(&x).ok_or("no valid base triangle and ray")?;
    let mesh = if affine {
        if mesh.normals().iter().all(|n| *n == mesh.normals()[0]) {
            return Err("the case is affine already".into());
        }
        nlrt_accel::BaseMesh::new(
            mesh.positions().to_vec(),
            vec![mesh.normals()[0]; 3],
            mesh.uvs().to_vec(),
            vec![[0, 1, 2]],
        )
        .map_err(|e| e.to_string())?
    } else {
        mesh
    };
    let surface = ShellSurface::new(mesh, object, T::ONE, tiling).map_err(|e| e.to_string())?;
    Ok((surface, ray))
}

/// [`shell_case`] with the base triangle's first direction at all three corners (an affine
/// prism, walked along the straight line where its frame is well-conditioned); an error
/// where the directions were equal already (the case itself is affine).
///
/// # Errors
/// As [`shell_case`].
pub fn affine_shell_case<T: Real>(
    data: &[u8],
) -> Result<(nlrt_accel::ShellSurface<T>, nlrt_shellmap::Ray<T>), String> {
    shell_case_with::<T>(data, true)
}

/// The shell traversal target: up to four object triangles in the unit tile (raw values;
/// out-of-tile objects must be rejected cleanly), tiling 1 to 8, one base triangle and a
/// ray. Same properties as [`fuzz_displacement`] (the straight walk's hits where the
/// triangle is affine and on its affine variant, the curved walk against brute force), and
/// the occlusion query agrees with the nearest hit on whether there is one.
pub fn fuzz_shell<T: Real>(data: &[u8]) {
    use nlrt_accel::TraversalStats;
    let Ok((mut surface, ray)) = shell_case::<T>(data) else {
        return;
    };
    // The straight walk, where the triangle is affine, and again with its first direction at
    // every corner: a hit is checked as every hit, and the occlusion query agrees with it;
    // the comparison with brute force (the same arithmetic) is the curved walk's.
    let affine = affine_shell_case::<T>(data).ok().map(|(s, _)| s);
    for straight in [
        (surface.straight_triangles() > 0).then_some(&surface),
        affine.as_ref(),
    ]
    .into_iter()
    .flatten()
    {
        let hit = straight.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default());
        assert_eq!(
            straight.occluded(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default()),
            hit.is_some(),
            "straight occlusion query against {hit:?}"
        );
        if let Some(hit) = hit {
            check_traversal_hit(&hit.hit, &hit);
        }
    }
    surface.set_straight_walk(false);
    let surface = surface;
    let fast = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default());
    // The occlusion query asks the same prisms with the same range until one holds a hit.
    assert_eq!(
        surface.occluded(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default()),
        fast.is_some(),
        "occlusion query against {fast:?}"
    );
    // A ray leaving the hit back towards the ray's origin: no panic, any hit finite, ahead
    // and not the triangle it leaves, and the occlusion query agreeing with it.
    if let Some(hit) = fast
        && let Some(back) = nlrt_shellmap::Ray::new(ray.at(hit.hit.t), -ray.dir)
    {
        let stats = &mut TraversalStats::default();
        let left = surface.intersect_leaving(&back, &hit, hit.hit.t, stats);
        if let Some(l) = left {
            assert!(l.hit.t.is_finite() && l.hit.t >= T::ZERO, "leaving {l:?}");
            assert!(
                (l.triangle, l.tile, l.object_triangle)
                    != (hit.triangle, hit.tile, hit.object_triangle),
                "leaving {hit:?} hit it again: {l:?}"
            );
        }
        assert_eq!(
            surface.occluded_leaving(&back, &hit, hit.hit.t, stats),
            left.is_some(),
            "leaving occlusion query against {left:?}"
        );
    }
    if let Some(hit) = fast {
        let h = hit.hit;
        check_traversal_hit(&h, &hit);
        let [x0, y0, x1, y1] = surface.roots(0).texels.map(i64::from);
        if (x1 - x0 + 1) * (y1 - y0 + 1) > BRUTE_FORCE_CELLS {
            return;
        }
        let brute = surface
            .intersect_brute_force(&ray, T::ZERO, T::INFINITY)
            .expect("brute force tests every tile the traversal tests");
        assert!(
            h.t >= brute.hit.t,
            "accelerated {hit:?} nearer than brute force {brute:?}"
        );
    }
}

/// Height-map side the scene-file target accepts: a 256^2 map of 16-bit samples is 128 KiB,
/// so no input makes the loader allocate more than a few MiB (the decoders' buffers are of
/// the same order), whatever its header claims.
pub const FUZZ_MAX_MAP_SIDE: usize = 256;

/// The scene-file loader target: the bytes are the TOML text, a 0 byte, the base mesh's OBJ
/// text, a 0 byte, and the rest the third file the TOML names (the height map, PNG or EXR by
/// the name's extension, or the shell object's OBJ); the files are handed out in the order
/// the loader asks for them, whatever their names. No panic, an error message that begins
/// with the path of a file the loader read, maps larger than [`FUZZ_MAX_MAP_SIDE`] refused from their header; a scene that loads
/// is built for nonlinear tracing in each precision it passes the precision check for and
/// renders a 4 x 4 image with one bounce, every pixel finite. Returns whether it loaded.
pub fn fuzz_scene_file(data: &[u8]) -> bool {
    use nlrt_render::scene::scene_file::{Source, load_from};
    use nlrt_render::trace::integrator::{RenderOptions, render};
    use nlrt_render::trace::method::Method;
    use std::cell::RefCell;
    use std::path::Path;
    let mut parts = data.splitn(3, |&b| b == 0);
    let files: Vec<&[u8]> = (0..3).map(|_| parts.next().unwrap_or(&[])).collect();
    let asked: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let read = |path: &Path| {
        let mut asked = asked.borrow_mut();
        let i = asked.len();
        asked.push(path.display().to_string());
        files
            .get(i)
            .map(|f| f.to_vec())
            .ok_or_else(|| format!("{}: fuzz input has no more files", path.display()))
    };
    let source = Source {
        read: &read,
        max_map_side: FUZZ_MAX_MAP_SIDE,
    };
    let scene = match load_from(Path::new("fuzz/scene.toml"), &source) {
        Ok(scene) => scene,
        Err(message) => {
            assert!(
                asked
                    .borrow()
                    .iter()
                    .any(|p| message.starts_with(p.as_str())),
                "an error names the file it is about: {message}"
            );
            return false;
        }
    };
    let opts = RenderOptions {
        width: 4,
        height: 4,
        spp: 1,
        bounces: 1,
    };
    // Every object (a file of `[[object]]` tables) traced as one.
    let nonlinear = |method: Method| method.build(&scene).expect("every scene supports it");
    let frames = [
        scene
            .check_precision::<f64>()
            .is_ok()
            .then(|| render(&scene, &nonlinear(Method::NONLINEAR_F64), &opts, &|_| {})),
        scene
            .check_precision::<f32>()
            .is_ok()
            .then(|| render(&scene, &nonlinear(Method::NONLINEAR_F32), &opts, &|_| {})),
    ];
    for frame in frames.iter().flatten() {
        assert!(
            frame.color.iter().flatten().all(|c| c.is_finite()),
            "non-finite pixel"
        );
    }
    true
}
