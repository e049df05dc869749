//! The displaced surface re-sampled as a geometry image (Carr et al. 2006): one world position
//! per texel corner of the tiled height map, each through Eq. 1 of the base triangle whose uv
//! triangle holds it. The surface is then the grid's quads, not clipped at base-triangle
//! edges: a texel straddling an edge joins corners of two triangles, which is where the method
//! differs from the clipped pre-tessellation.

use crate::scene::scenes::{Content, Scene};
use crate::trace::tracer::{TraceHit, Tracer, ray_in};
use nlrt_accel::HEIGHT_ONE;
use nlrt_baselines::GeometryImage;
use nlrt_poly::glam::{DVec2, DVec3};
use nlrt_poly::{Real, Vector3};

/// Why a scene has no geometry image.
pub fn unsupported_reason(scene: &Scene) -> Option<&'static str> {
    let Content::Displacement(field) = &scene.content else {
        return Some("geometry images hold height fields, not instanced objects");
    };
    let Some(side) = field.square_side() else {
        return Some("the map is not square with a power-of-two side");
    };
    let cells = scene.tiling * side as f64;
    if !(cells.fract() == 0.0 && (cells as usize).is_power_of_two()) {
        return Some("the tiled map's side is not a power of two");
    }
    if scene
        .uvs
        .iter()
        .any(|uv| !(0.0..=1.0).contains(&uv.x) || !(0.0..=1.0).contains(&uv.y))
    {
        return Some("uvs outside [0, 1]: a geometry image is one chart over the unit square");
    }
    let area: f64 = scene
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| scene.uvs[v as usize]);
            ((b - a).perp_dot(c - a) * 0.5).abs()
        })
        .sum();
    // Charts may cover the square at most once; 1e-9 absorbs the rounding of the sum.
    if area > 1.0 + 1e-9 {
        return Some("uv charts overlap: a geometry image holds one surface point per uv");
    }
    None
}

/// The geometry image of a displacement scene in precision `T` and the base triangle of each
/// corner; `None` with [`unsupported_reason`].
#[must_use]
pub fn geometry_image<T: Real>(scene: &Scene) -> Option<(GeometryImage<T>, Vec<u32>)> {
    if unsupported_reason(scene).is_some() {
        return None;
    }
    let Content::Displacement(field) = &scene.content else {
        return None;
    };
    let n = (scene.tiling * field.width() as f64) as usize;
    let w = n + 1;
    let mut positions = vec![DVec3::splat(f64::NAN); w * w];
    let mut owner = vec![u32::MAX; w * w];
    // The shell's floor at the midlevel's depth (one chart: no seams to weld).
    let floor = nlrt_accel::shell_floor::<f64>(
        &scene.positions,
        &scene.normals,
        scene.height_scale,
        scene.midlevel,
    );
    for (k, t) in scene.triangles.iter().enumerate() {
        let uv = t.map(|v| scene.uvs[v as usize] * n as f64);
        let det = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
        if det == 0.0 {
            continue; // no inverse of Eq. 2-3: the chart has no area here
        }
        let (p, nrm) = (
            t.map(|v| floor[v as usize]),
            t.map(|v| scene.normals[v as usize] * scene.height_scale),
        );
        let lo = uv[0].min(uv[1]).min(uv[2]).floor().max(DVec2::ZERO);
        let hi = uv[0]
            .max(uv[1])
            .max(uv[2])
            .ceil()
            .min(DVec2::splat(n as f64));
        for j in lo.y as usize..=hi.y as usize {
            for i in lo.x as usize..=hi.x as usize {
                let d = DVec2::new(i as f64, j as f64) - uv[0];
                let alpha = d.perp_dot(uv[2] - uv[0]) / det;
                let beta = (uv[1] - uv[0]).perp_dot(d) / det;
                if !(alpha >= 0.0 && beta >= 0.0 && alpha + beta <= 1.0) {
                    continue;
                }
                let h = f64::from(field.sample(i as i64, j as i64)) / f64::from(HEIGHT_ONE);
                let at = |m: usize| p[m] + nrm[m] * h;
                positions[j * w + i] = at(0) + (at(1) - at(0)) * alpha + (at(2) - at(0)) * beta;
                owner[j * w + i] = k as u32;
            }
        }
    }
    let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
    let image = GeometryImage::new(n, positions.into_iter().map(v).collect()).ok()?;
    Some((image, owner))
}

/// Geometry-image ray tracing in precision `T`.
pub struct GeometryImageTracer<T: Real> {
    image: GeometryImage<T>,
    owner: Vec<u32>,
}

impl<T: Real> GeometryImageTracer<T> {
    /// Samples `scene` into a geometry image; `None` for scenes it cannot hold.
    #[must_use]
    pub fn new(scene: &Scene) -> Option<Self> {
        let (image, owner) = geometry_image(scene)?;
        Some(Self { image, owner })
    }
}

impl<T: Real> Tracer for GeometryImageTracer<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let hit = self.image.intersect(&ray, t_min, t_max)?;
        let n = hit.normal;
        let n = n.to_dvec3().normalize_or_zero();
        if n == DVec3::ZERO {
            return None;
        }
        let [x, y] = hit.quad.map(|c| c as usize);
        Some(TraceHit {
            t: hit.t.to_f64(),
            normal: if n.dot(dir) > 0.0 { -n } else { n },
            id: self.owner[y * (self.image.side() + 1) + x],
        })
    }

    fn memory_bytes(&self) -> usize {
        self.image.memory_bytes() + self.owner.len() * std::mem::size_of::<u32>()
    }
}
