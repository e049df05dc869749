//! Animated base meshes: how a scene's base mesh moves from frame to frame ([`Motion`]), as
//! a procedural deformation of its rest pose ([`Deformation`]) or as a sequence of poses read
//! from OBJ files of identical topology and uvs. A pose ([`Pose`]) is a full set of vertex
//! positions and normals; `nlrt animate` hands it to the surfaces' `set_pose`.
//!
//! Deformations are maps of world space, `x -> f(x)`, applied to every vertex; normals follow
//! by the cofactor of the map's Jacobian (`det J * J^-T n`, the transform of a surface normal,
//! which stays defined where the map flattens the mesh), keeping each normal's length (the
//! shell's thickness). Equal inputs give equal outputs, so the duplicated vertices of a uv
//! seam stay bit-identical and the shell stays closed.

use nlrt_poly::glam::DVec3;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// A procedural deformation of a base mesh, in the frame of its bounding box (centre at the
/// origin, largest half-extent 1, `y` up as in every built-in scene).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Deformation {
    /// A standing wave across `x` and `z`, rising and falling along `y` (the mountain's ground
    /// swell).
    Wave,
    /// Bends along `y` in the `xy` plane while twisting about `y` (the cylinder).
    Bend,
    /// Twists about `y` by an angle growing along `y`.
    Twist,
    /// Swells and shrinks a ring's tube in three waves around the ring (the tori breathe).
    Breathe,
    /// Squashes along `y` and widens across it (the Cornell sphere); at amplitude 2.5 it is
    /// flat at mid-cycle.
    Squash,
}

impl Deformation {
    /// Every deformation, for listings.
    pub const ALL: [Deformation; 5] = [
        Deformation::Wave,
        Deformation::Bend,
        Deformation::Twist,
        Deformation::Breathe,
        Deformation::Squash,
    ];

    /// Name in scene files and on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Deformation::Wave => "wave",
            Deformation::Bend => "bend",
            Deformation::Twist => "twist",
            Deformation::Breathe => "breathe",
            Deformation::Squash => "squash",
        }
    }

    /// The deformation named `name`.
    ///
    /// # Errors
    /// An unknown name; the message lists the known ones.
    pub fn from_name(name: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|d| d.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|d| d.name()).collect();
                format!(
                    "unknown deformation '{name}' (deformations: {})",
                    names.join(", ")
                )
            })
    }

    /// The deformed point of `q` (normalised coordinates) at `phase` (radians of the cycle;
    /// 0 is the rest pose) with `amplitude` (1 the built-in strength). `ring` is the mean
    /// distance of the rest vertices from the `y` axis ([`Deformation::Breathe`]).
    #[must_use]
    fn map(self, q: DVec3, phase: f64, amplitude: f64, ring: f64) -> DVec3 {
        let a = amplitude;
        match self {
            Deformation::Wave => {
                // Amplitude 0.1 of the half-extent: a swell the eye reads, a third of the
                // mountain's relief.
                let lift = 0.1 * a * phase.sin() * (TAU * q.x + 1.0).sin() * (0.5 * PI * q.z).cos();
                DVec3::new(q.x, q.y + lift, q.z)
            }
            Deformation::Bend => {
                // Curvature 0.6 per half-extent: the ends turn by 0.6 rad (34 degrees) and the
                // bend's radius (1.7) stays well outside the cylinder's displaced tube (0.7),
                // so the inner side compresses without folding; the twist is half a radian
                // per half-extent.
                let twisted = rotate_about_y(q, 0.5 * a * phase.sin() * q.y);
                bend_xy(twisted, 0.6 * a * phase.sin())
            }
            // 0.8 rad per half-extent: a visible screw that leaves triangles unfolded.
            Deformation::Twist => rotate_about_y(q, 0.8 * a * phase.sin() * q.y),
            Deformation::Breathe => {
                let rho = q.x.hypot(q.z);
                // The ring point nearest `q` (the axis itself maps to the centre).
                let centre = if rho > 0.0 {
                    DVec3::new(q.x / rho * ring, 0.0, q.z / rho * ring)
                } else {
                    DVec3::ZERO
                };
                // The tube swells and shrinks by 30%, in three waves around the ring.
                let swell = 1.0 + 0.3 * a * phase.sin() * (3.0 * q.z.atan2(q.x)).sin();
                centre + (q - centre) * swell
            }
            Deformation::Squash => {
                // Down to 60% of the height at mid-cycle (flat at amplitude 2.5).
                let s = 1.0 - 0.4 * a * 0.5 * (1.0 - phase.cos());
                DVec3::new(
                    q.x * (1.0 + 0.5 * (1.0 - s)),
                    q.y * s,
                    q.z * (1.0 + 0.5 * (1.0 - s)),
                )
            }
        }
    }
}

/// `q` rotated about the `y` axis by `angle`.
fn rotate_about_y(q: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    DVec3::new(c * q.x - s * q.z, q.y, s * q.x + c * q.z)
}

/// `sin(x) / x`, 1 at 0 (the series' next term is below f64 rounding for |x| < 1e-4).
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// Bends the `y` axis into an arc of curvature `kappa` in the `xy` plane (the point at height
/// `y` turns by `kappa y`), written without `1 / kappa` so that it is smooth through the
/// straight pose: `x' = x cos t + y sin(t/2) sinc(t/2)`, `y' = y sinc(t) - x sin t`.
fn bend_xy(q: DVec3, kappa: f64) -> DVec3 {
    let t = kappa * q.y;
    let half = 0.5 * t;
    DVec3::new(
        q.x * t.cos() + q.y * half.sin() * sinc(half),
        q.y * sinc(t) - q.x * t.sin(),
        q.z,
    )
}

/// One pose of a base mesh: every vertex's position and normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Positions.
    pub positions: Vec<DVec3>,
    /// Normals (the shell's direction and thickness per vertex, as in the scene).
    pub normals: Vec<DVec3>,
}

/// How a scene's base mesh moves.
#[derive(Clone, Debug)]
pub enum Motion {
    /// It does not (a scene file without an `[animation]` section).
    Static,
    /// A procedural deformation of the rest pose, one cycle over the frames.
    Deform {
        /// Which.
        deformation: Deformation,
        /// Strength (1 is the built-in one).
        amplitude: f64,
    },
    /// Poses read from files (frame `k` shows pose `k` modulo their count).
    Frames(Arc<[Pose]>),
}

impl Motion {
    /// The built-in motion of deformation `d` at amplitude 1.
    #[must_use]
    pub fn deform(deformation: Deformation) -> Self {
        Motion::Deform {
            deformation,
            amplitude: 1.0,
        }
    }

    /// A one-line description.
    #[must_use]
    pub fn describe(&self) -> String {
        match self {
            Motion::Static => "static".into(),
            Motion::Deform {
                deformation,
                amplitude,
            } => format!("{} (amplitude {amplitude})", deformation.name()),
            Motion::Frames(poses) => format!("{} poses from OBJ files", poses.len()),
        }
    }

    /// The pose of frame `frame` of `frames` of a mesh whose rest pose is `positions`,
    /// `normals`; `None` for [`Motion::Static`].
    #[must_use]
    pub fn pose(
        &self,
        positions: &[DVec3],
        normals: &[DVec3],
        frame: usize,
        frames: usize,
    ) -> Option<Pose> {
        match self {
            Motion::Static => None,
            Motion::Frames(poses) => poses.get(frame % poses.len().max(1)).cloned(),
            Motion::Deform {
                deformation,
                amplitude,
            } => {
                let phase = TAU * frame as f64 / frames.max(1) as f64;
                Some(deform(positions, normals, *deformation, *amplitude, phase))
            }
        }
    }
}

/// Step of the central differences of the Jacobian, in normalised coordinates: the
/// deformations' third derivatives are O(10), so the truncation error is about 1e-9 and the
/// rounding error about 1e-16 / 1e-5 = 1e-11, both far below what a normal's direction
/// needs.
const JACOBIAN_STEP: f64 = 1e-5;

/// `positions` and `normals` deformed by `d` at `phase`.
fn deform(
    positions: &[DVec3],
    normals: &[DVec3],
    d: Deformation,
    amplitude: f64,
    phase: f64,
) -> Pose {
    let (lo, hi) = positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let centre = (lo + hi) * 0.5;
    let half = ((hi - lo) * 0.5).max_element();
    let scale = if half > 0.0 && half.is_finite() {
        half
    } else {
        1.0
    };
    let ring = if positions.is_empty() {
        0.0
    } else {
        positions
            .iter()
            .map(|p| {
                let q = (*p - centre) / scale;
                q.x.hypot(q.z)
            })
            .sum::<f64>()
            / positions.len() as f64
    };
    let f = |q: DVec3| d.map(q, phase, amplitude, ring);
    let mut out = Pose {
        positions: Vec::with_capacity(positions.len()),
        normals: Vec::with_capacity(positions.len()),
    };
    for (p, n) in positions.iter().zip(normals) {
        let q = (*p - centre) / scale;
        out.positions.push(centre + f(q) * scale);
        let h = JACOBIAN_STEP;
        let column = |axis: DVec3| (f(q + axis * h) - f(q - axis * h)) / (2.0 * h);
        let (j0, j1, j2) = (column(DVec3::X), column(DVec3::Y), column(DVec3::Z));
        // det(J) J^-T n: the columns of the cofactor matrix are j1 x j2, j2 x j0, j0 x j1.
        let m = j1.cross(j2) * n.x + j2.cross(j0) * n.y + j0.cross(j1) * n.z;
        out.normals.push(m.normalize_or_zero() * n.length());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring_mesh() -> (Vec<DVec3>, Vec<DVec3>) {
        let mut p = Vec::new();
        let mut n = Vec::new();
        for i in 0..24 {
            for j in 0..8 {
                let (a, b) = (TAU * i as f64 / 24.0, TAU * j as f64 / 8.0);
                let normal = DVec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos());
                p.push(DVec3::new(a.cos(), 0.0, a.sin()) + normal * 0.3);
                n.push(normal);
            }
        }
        (p, n)
    }

    /// Phase 0 is the rest pose for every deformation (the tree is built for it), and each
    /// deformation moves the mesh at mid-cycle.
    #[test]
    fn the_cycle_starts_at_rest_and_moves() {
        let (p, n) = ring_mesh();
        for d in Deformation::ALL {
            let motion = Motion::deform(d);
            let rest = motion.pose(&p, &n, 0, 8).unwrap();
            for (a, b) in rest.positions.iter().zip(&p) {
                assert!((*a - *b).length() < 1e-12, "{d:?}");
            }
            for (a, b) in rest.normals.iter().zip(&n) {
                assert!((*a - *b).length() < 1e-6, "{d:?}: {a} vs {b}");
            }
            let moved = motion.pose(&p, &n, 2, 8).unwrap();
            let furthest = moved
                .positions
                .iter()
                .zip(&p)
                .map(|(a, b)| (*a - *b).length())
                .fold(0.0, f64::max);
            assert!(furthest > 0.02, "{d:?} moves the mesh by {furthest}");
        }
    }

    /// Normals follow the map: a twist turns a vertical cylinder into itself, so every
    /// twisted normal is the radial direction at the twisted point; a horizontal disc stays
    /// horizontal, its normals +y.
    #[test]
    fn normals_are_transformed_by_the_cofactor_of_the_jacobian() {
        let (mut p, mut n) = (Vec::new(), Vec::new());
        for k in 0..40 {
            let (a, y) = (TAU * k as f64 / 40.0, -1.0 + 2.0 * (k % 7) as f64 / 6.0);
            p.push(DVec3::new(a.cos(), y, a.sin()));
            n.push(DVec3::new(a.cos(), 0.0, a.sin()) * 0.2);
            p.push(DVec3::new(0.5 * a.cos(), 0.25, 0.5 * a.sin()));
            n.push(DVec3::Y);
        }
        let twisted = Motion::deform(Deformation::Twist)
            .pose(&p, &n, 1, 4)
            .unwrap();
        for k in 0..40 {
            let (q, m) = (twisted.positions[2 * k], twisted.normals[2 * k]);
            let radial = DVec3::new(q.x, 0.0, q.z).normalize() * 0.2;
            assert!((m - radial).length() < 1e-8, "{m} vs {radial}");
            assert!((twisted.normals[2 * k + 1] - DVec3::Y).length() < 1e-8);
        }
        // Squash at amplitude 2.5, half a cycle, is flat: points on y = 0, a top normal
        // along +y, and no NaN among the normals whose direction the flat map loses.
        let flat = Motion::Deform {
            deformation: Deformation::Squash,
            amplitude: 2.5,
        }
        .pose(&p, &n, 1, 2)
        .unwrap();
        for (q, m) in flat.positions.iter().zip(&flat.normals) {
            assert!(q.y.abs() < 1e-12, "{q}");
            assert!(m.is_finite());
        }
        assert!((flat.normals[1] - DVec3::Y).length() < 1e-9);
    }

    #[test]
    fn names_round_trip_and_unknown_ones_list_the_known() {
        for d in Deformation::ALL {
            assert_eq!(Deformation::from_name(d.name()), Ok(d));
        }
        let e = Deformation::from_name("wobble").unwrap_err();
        assert!(e.contains("wobble") && e.contains("breathe"), "{e}");
    }

    #[test]
    fn frames_cycle_through_their_poses() {
        let pose = |x: f64| Pose {
            positions: vec![DVec3::splat(x)],
            normals: vec![DVec3::Y],
        };
        let motion = Motion::Frames(vec![pose(0.0), pose(1.0)].into());
        assert_eq!(motion.pose(&[], &[], 3, 10), Some(pose(1.0)));
        assert_eq!(Motion::Static.pose(&[], &[], 3, 10), None);
    }
}
