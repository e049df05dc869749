//! Test geometry: small base meshes and height maps (random and adversarial) for the
//! accelerator tests and fuzz targets.

use nlrt_accel::{BaseMesh, HeightField, Wrap};
use nlrt_poly::{Real, Vector2, Vector3};

/// SplitMix64: a small, fast, seedable generator (Steele et al. 2014) for test inputs.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// From a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Kinds of height map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Independent uniform samples.
    Random,
    /// Mostly 0 with isolated full-height spikes (thin features; like the fur map).
    Spikes,
    /// Plateaus of 4 x 4 samples at a few levels (many flat texels and flat microtriangles).
    Plateaus,
    /// Alternating 0 / max samples (the steepest possible map).
    Checker,
}

/// A `side x side` map of `kind`.
pub fn height_map(side: usize, kind: MapKind, wrap: Wrap, seed: u64) -> HeightField {
    let mut rng = SplitMix64::new(seed);
    let samples = (0..side * side)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            match kind {
                MapKind::Random => (rng.next_u64() >> 48) as u16,
                MapKind::Spikes => {
                    if rng.next_u64().is_multiple_of(17) {
                        u16::MAX
                    } else {
                        0
                    }
                }
                MapKind::Plateaus => {
                    let cell = (i / 4 * 7 + j / 4 * 13) % 5;
                    (cell as u16) * 16000
                }
                MapKind::Checker => {
                    if (i + j).is_multiple_of(2) {
                        u16::MAX
                    } else {
                        0
                    }
                }
            }
        })
        .collect();
    HeightField::new(side, side, samples, wrap).expect("valid side")
}

/// An `n x n` grid of quads over `[0, 1]^2`, two triangles each, bent into a bump of height
/// `bend` (so normals vary and prisms are curved), uvs equal to `(x, y)`. With `degenerate`,
/// every fifth triangle has its uvs collapsed: to a point for odd triangles, onto a line for
/// even ones (Fig. 4 and 9 of the paper).
pub fn grid_mesh<T: Real>(n: usize, bend: f64, degenerate: bool) -> BaseMesh<T> {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let f =
        |x: f64, y: f64| bend * (std::f64::consts::PI * x).sin() * (std::f64::consts::PI * y).sin();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            let pi = std::f64::consts::PI;
            let dx = bend * pi * (pi * x).cos() * (pi * y).sin();
            let dy = bend * pi * (pi * x).sin() * (pi * y).cos();
            let len = (dx * dx + dy * dy + 1.0).sqrt();
            positions.push(T::Vec3::new(
                T::from_f64(x),
                T::from_f64(y),
                T::from_f64(f(x, y)),
            ));
            normals.push(T::Vec3::new(
                T::from_f64(-dx / len),
                T::from_f64(-dy / len),
                T::from_f64(1.0 / len),
            ));
            uvs.push(T::Vec2::new(T::from_f64(x), T::from_f64(y)));
        }
    }
    let mut triangles = Vec::new();
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    if degenerate {
        // Give degenerate triangles their own vertices so their neighbours keep proper uvs.
        for t in (0..triangles.len()).step_by(5) {
            let tri = triangles[t];
            let base = positions.len() as u32;
            for (k, &v) in tri.iter().enumerate() {
                positions.push(positions[v as usize]);
                normals.push(normals[v as usize]);
                let uv = uvs[tri[0] as usize];
                let uv = if t % 2 == 1 {
                    uv // a point
                } else {
                    // a line: the three uvs on the segment from uv(tri[0]) to uv(tri[1])
                    let e = uvs[tri[1] as usize] - uv;
                    uv + e * T::from_f64(k as f64 * 0.5)
                };
                uvs.push(uv);
            }
            triangles[t] = [base, base + 1, base + 2];
        }
    }
    BaseMesh::new(positions, normals, uvs, triangles).expect("valid grid")
}

/// A ray aimed from above at a random point of `[0, 1]^2` with the elevation of its direction
/// above the xy plane between `min_elevation` and 90 degrees (small values graze).
pub fn ray_from_above(rng: &mut SplitMix64, min_elevation: f64) -> ([f64; 3], [f64; 3]) {
    let u = SplitMix64::unit;
    let target = [u(rng) * 1.2 - 0.1, u(rng) * 1.2 - 0.1, u(rng) * 0.3];
    let elevation = min_elevation + (std::f64::consts::FRAC_PI_2 - min_elevation) * u(rng);
    let azimuth = 2.0 * std::f64::consts::PI * u(rng);
    let dir = [
        elevation.cos() * azimuth.cos(),
        elevation.cos() * azimuth.sin(),
        -elevation.sin(),
    ];
    let back = 3.0;
    (
        [
            target[0] - back * dir[0],
            target[1] - back * dir[1],
            target[2] - back * dir[2],
        ],
        dir,
    )
}

/// `n` random triangles in the unit tile; every fourth one has a vertex on a tile edge
/// (u or v exactly 0 or 1), where neighbouring tiles meet.
pub fn random_object<T: Real>(n: usize, seed: u64) -> Vec<[T::Vec3; 3]> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|i| {
            let centre = [rng.unit(), rng.unit(), 0.2 + 0.6 * rng.unit()];
            let mut tri = [[0.0f64; 3]; 3];
            for v in &mut tri {
                for (c, x) in v.iter_mut().enumerate() {
                    *x = (centre[c] + 0.3 * (rng.unit() - 0.5)).clamp(0.0, 1.0);
                }
            }
            if i % 4 == 0 {
                tri[0][0] = if rng.unit() < 0.5 { 0.0 } else { 1.0 };
            }
            tri.map(|p| T::Vec3::new(T::from_f64(p[0]), T::from_f64(p[1]), T::from_f64(p[2])))
        })
        .collect()
}

/// Asserts that an occlusion query (`occluded(t_max)` over `[0, t_max]`) agrees with the
/// nearest hit's distance `nearest` on the same ray: blocked over the whole ray exactly when
/// there is a hit, and open up to half its distance.
///
/// # Panics
/// Where they disagree, naming `ray`.
pub fn assert_occlusion_agrees<T: Real>(
    occluded: impl Fn(T) -> bool,
    nearest: Option<T>,
    ray: &dyn core::fmt::Debug,
) {
    assert_eq!(occluded(T::INFINITY), nearest.is_some(), "{ray:?}");
    if let Some(t) = nearest {
        assert!(
            !occluded(t / T::TWO),
            "open before the nearest hit: {ray:?}"
        );
    }
}
