//! Surface reflectance (diffuse and glossy) with its importance sampling, and the renderer's
//! random numbers.

use nlrt_poly::glam::DVec3;
use rand_pcg::Pcg64;
use rand_pcg::rand_core::Rng as _;

/// The initial state of every stream. Any constant works: PCG streams with different
/// increments never share a sequence, so the stream index alone tells pixels apart, and a
/// fixed state keeps every render reproducible.
const STREAM_STATE: u128 = 0xcafe_f00d_d15e_a5e5_7e57_ab1e_0dd5_eed5;

/// The renderer's random numbers: PCG-XSL-RR 128/64 ([`rand_pcg::Pcg64`]), one stream per
/// pixel, so an image does not depend on how rows are scheduled on threads.
///
/// ```
/// use nlrt_render::scene::material::Rng;
/// let (mut a, mut b) = (Rng::stream(3), Rng::stream(3));
/// let x = a.next_f64();
/// assert!((0.0..1.0).contains(&x) && x == b.next_f64());
/// assert_ne!(Rng::stream(4).next_f64(), x);
/// ```
pub struct Rng(Pcg64);

impl Rng {
    /// Stream `index` (e.g. a pixel's index in the image).
    #[must_use]
    pub fn stream(index: u64) -> Self {
        Self(Pcg64::new(STREAM_STATE, u128::from(index)))
    }

    /// A uniform number in `[0, 1)`: the top 53 bits of the next output, so every value is
    /// an exact multiple of 2^-53.
    pub fn next_f64(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A surface's reflectance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian, albedo 0.5.
    Diffuse,
    /// A normalised Phong lobe (specular reflectance 0.5, the given exponent) around the
    /// mirror direction: the glossy material, whose bounce rays stay coherent around the
    /// reflection instead of spreading over the hemisphere.
    Glossy {
        /// Phong exponent (sharper for larger).
        exponent: f64,
    },
}

/// Reflectance of both materials.
const ALBEDO: f64 = 0.5;

impl Material {
    /// The glossy material of the built-in scenes and of scene files (`material = "glossy"`).
    pub const GLOSSY: Material = Material::Glossy { exponent: 40.0 };

    /// `pi` times the BRDF for light arriving from `light` seen along `dir` (towards the
    /// surface) at normal `n`.
    #[must_use]
    pub fn brdf_times_pi(self, n: DVec3, dir: DVec3, light: DVec3) -> f64 {
        match self {
            Material::Diffuse => ALBEDO,
            Material::Glossy { exponent } => {
                let mirror = dir - n * (2.0 * dir.dot(n));
                let c = mirror.dot(light).max(0.0);
                ALBEDO * (exponent + 2.0) * 0.5 * c.powf(exponent)
            }
        }
    }

    /// A bounce direction and the path weight (BRDF times cosine over the pdf); `None` when
    /// the sampled direction goes below the surface (the path ends).
    pub fn sample(self, n: DVec3, dir: DVec3, rng: &mut Rng) -> Option<(DVec3, f64)> {
        match self {
            Material::Diffuse => Some((cosine_direction(n, rng), ALBEDO)),
            Material::Glossy { exponent } => {
                let mirror = (dir - n * (2.0 * dir.dot(n))).normalize();
                // Phong lobe sampling: pdf (e + 1) / (2 pi) cos^e around the mirror direction.
                let (r1, r2) = (rng.next_f64(), rng.next_f64());
                let cos_a = r2.powf(1.0 / (exponent + 1.0));
                let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                let phi = std::f64::consts::TAU * r1;
                let next = frame_around(mirror, phi.cos() * sin_a, phi.sin() * sin_a, cos_a);
                let cos = next.dot(n);
                (cos > 0.0).then(|| (next, ALBEDO * (exponent + 2.0) / (exponent + 1.0) * cos))
            }
        }
    }
}

/// `x t + y b + z n` for an orthonormal frame `(t, b, n)` around the unit vector `n`.
fn frame_around(n: DVec3, x: f64, y: f64, z: f64) -> DVec3 {
    let helper = if n.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
    let t = n.cross(helper).normalize();
    let b = n.cross(t);
    (t * x + b * y + n * z).normalize()
}

/// Cosine-weighted direction around `n`.
fn cosine_direction(n: DVec3, rng: &mut Rng) -> DVec3 {
    let (r1, r2) = (rng.next_f64(), rng.next_f64());
    let phi = std::f64::consts::TAU * r1;
    let r = r2.sqrt();
    frame_around(n, r * phi.cos(), r * phi.sin(), (1.0 - r2).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The BRDF used for next-event estimation and the sampling used for bounces must describe
    /// the same material, or images are biased: their directional albedos (the integral of
    /// BRDF times cosine over the hemisphere) agree, estimated independently: by uniform
    /// hemisphere sampling of `brdf_times_pi`, and by the mean bounce weight of `sample`.
    #[test]
    fn sampling_and_brdf_agree_on_the_albedo() {
        let n = DVec3::new(0.2, 0.9, -0.1).normalize();
        for material in [Material::Diffuse, Material::GLOSSY] {
            for incidence in [0.0f64, 0.5, 1.2] {
                // A direction towards the surface at `incidence` from the normal.
                let t = n.cross(DVec3::X).normalize();
                let dir = -(n * incidence.cos() + t * incidence.sin());
                let mut rng = Rng::stream(7);
                let count = 400_000;
                let mut by_sampling = 0.0;
                let mut by_brdf = 0.0;
                for _ in 0..count {
                    if let Some((_, w)) = material.sample(n, dir, &mut rng) {
                        by_sampling += w;
                    }
                    // Uniform hemisphere: pdf 1 / (2 pi); BRDF = brdf_times_pi / pi.
                    let (r1, r2) = (rng.next_f64(), rng.next_f64());
                    let z = r1;
                    let s = (1.0 - z * z).sqrt();
                    let phi = std::f64::consts::TAU * r2;
                    let l = frame_around(n, s * phi.cos(), s * phi.sin(), z);
                    by_brdf += material.brdf_times_pi(n, dir, l) * z * 2.0;
                }
                let (a, b) = (by_sampling / count as f64, by_brdf / count as f64);
                // Monte Carlo: a few standard errors of the noisier (uniform) estimate.
                assert!(
                    (a - b).abs() < 0.02,
                    "{material:?} at {incidence}: {a} vs {b}"
                );
                assert!(a <= ALBEDO + 0.01, "{material:?}: energy {a}");
            }
        }
    }
}
