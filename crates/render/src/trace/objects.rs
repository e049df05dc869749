//! Scenes of several objects ([`crate::scene::scenes::Scene::others`]) traced as one: each object
//! keeps the acceleration data of its own method (a displaced surface's TLAS and min-max
//! pyramid, a shell's TLAS and object BVH, a tessellation's BVH), and a ray asks them in
//! turn with its range cut at the nearest hit so far.
//!
//! The objects' own top levels are the top level: each begins with its root box, so an
//! object the ray misses costs one box test. That is a flat list, chosen because an object
//! of one kind cannot sit in another kind's tree (a displaced prism and a shell prism carry
//! different leaves); [`crate::scene::scene_file::MAX_OBJECTS`] keeps the list short enough
//! for it.
//!
//! Hit ids run through the objects in order: object `k`'s base triangle `i` is id `i` plus
//! the triangles of the objects before it ([`crate::scene::scenes::Scene::object_of`] inverts it).

use crate::trace::tracer::{TraceHit, Tracer};
use nlrt_poly::glam::DVec3;

/// Several objects' tracers traced as one surface.
pub struct ObjectUnion<Tr> {
    /// Each object's tracer and the hit id of its first base triangle.
    parts: Vec<(Tr, u32)>,
}

impl<Tr: Tracer> ObjectUnion<Tr> {
    /// The union of `parts`, each an object's tracer with its base triangle count, in the
    /// scene's object order.
    ///
    /// # Panics
    /// More base triangles over all objects than `u32` ids can name: scene files refuse such
    /// objects when loaded, and no built-in scene comes near.
    #[must_use]
    pub fn new(parts: impl IntoIterator<Item = (Tr, usize)>) -> Self {
        let mut first = 0u32;
        let parts = parts
            .into_iter()
            .map(|(tracer, triangles)| {
                let id = first;
                first = u32::try_from(triangles)
                    .ok()
                    .and_then(|n| first.checked_add(n))
                    .expect("fewer than 2^32 base triangles over all objects");
                (tracer, id)
            })
            .collect();
        Self { parts }
    }

    /// The objects' tracers, in order (to move each, as `nlrt animate` does).
    pub fn tracers_mut(&mut self) -> impl Iterator<Item = &mut Tr> {
        self.parts.iter_mut().map(|(t, _)| t)
    }

    /// The objects' tracers, in order.
    pub fn tracers(&self) -> impl Iterator<Item = &Tr> {
        self.parts.iter().map(|(t, _)| t)
    }
}

impl<Tr: Tracer> Tracer for ObjectUnion<Tr> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let mut nearest: Option<TraceHit> = None;
        for (tracer, first_id) in &self.parts {
            let limit = nearest.map_or(t_max, |h| h.t);
            if let Some(hit) = tracer.intersect(origin, dir, t_min, limit)
                // A later object at exactly the same distance leaves the earlier one's hit.
                && nearest.is_none_or(|n| hit.t < n.t)
            {
                nearest = Some(TraceHit {
                    id: hit.id + first_id,
                    ..hit
                });
            }
        }
        nearest
    }

    fn memory_bytes(&self) -> usize {
        self.parts.iter().map(|(t, _)| t.memory_bytes()).sum()
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        self.parts
            .iter()
            .any(|(tracer, _)| tracer.occluded(origin, dir, t_min, t_max))
    }
}

#[cfg(test)]
mod tests {
    use super::ObjectUnion;
    use crate::trace::tracer::{TraceHit, Tracer};
    use nlrt_poly::glam::DVec3;

    /// A plane `x = at` hit from either side, every hit id `id`.
    struct Wall {
        at: f64,
        id: u32,
    }

    impl Tracer for Wall {
        fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
            let t = (self.at - o.x) / d.x;
            (t > t_min && t <= t_max).then_some(TraceHit {
                t,
                normal: DVec3::X,
                id: self.id,
            })
        }

        fn memory_bytes(&self) -> usize {
            8
        }
    }

    /// The nearest object's hit, its id shifted by the triangles before it; the range is
    /// respected; ties keep the earlier object; memory adds up.
    #[test]
    fn the_nearest_object_answers_with_its_id_shifted() {
        let union = ObjectUnion::new([
            (Wall { at: 5.0, id: 2 }, 10),
            (Wall { at: 3.0, id: 1 }, 4),
            (Wall { at: 5.0, id: 0 }, 7),
        ]);
        let hit = |t_min, t_max| union.intersect(DVec3::ZERO, DVec3::X, t_min, t_max);
        assert_eq!(
            hit(0.0, f64::INFINITY).map(|h| (h.t, h.id)),
            Some((3.0, 11))
        );
        assert_eq!(hit(3.0, f64::INFINITY).map(|h| (h.t, h.id)), Some((5.0, 2)));
        assert_eq!(hit(0.0, 2.5), None);
        assert_eq!(hit(5.0, 9.0), None);
        let blocked = |t_min, t_max| union.occluded(DVec3::ZERO, DVec3::X, t_min, t_max);
        assert!(blocked(0.0, 3.0) && blocked(4.0, 5.0) && !blocked(0.0, 2.5) && !blocked(5.0, 9.0));
        assert_eq!(union.memory_bytes(), 24);
    }
}
