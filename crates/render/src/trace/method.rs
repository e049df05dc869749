//! The methods a scene can be rendered with, by name ([`Method`]): which scenes each
//! supports, and the [`Tracer`] each builds.

use crate::scene::scenes::{Content, Scene};
use crate::trace::geometry_image::GeometryImageTracer;
use crate::trace::methods::{
    ConeTracer, Marching, Nonlinear, Projective, TessellationFree, VolumeMarching,
};
use crate::trace::objects::ObjectUnion;
use crate::trace::tessellate::Tessellated;
use crate::trace::tracer::Tracer;
use nlrt_baselines::Rectification;
use std::fmt;

/// A way of intersecting rays with a scene's displaced surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Nonlinear ray tracing in single precision.
    NonlinearF32,
    /// Nonlinear ray tracing in double precision.
    NonlinearF64,
    /// Tessellation-free displacement mapping (Thonat et al. 2021: world-space node boxes by
    /// affine arithmetic, flat world microtriangles) in single precision; displacement only.
    AffineF32,
    /// Tessellation-free displacement mapping in double precision; displacement only.
    AffineF64,
    /// Geometry-image ray tracing (Carr et al. 2006: the displaced surface re-sampled on the
    /// texel grid, a min-max pyramid of world boxes walked by hit/miss links) in single
    /// precision; height fields on one uv chart only.
    GeometryImageF32,
    /// Geometry-image ray tracing in double precision.
    GeometryImageF64,
    /// Smooth shell mapping by ray marching (Jeschke et al. 2007: canonical-space sampling
    /// with image-space error correction, 2 samples per texel, binary-search refinement) in
    /// single precision; instanced objects are voxelised in their tile (its 3D textures).
    MarchingF32,
    /// Smooth shell mapping by ray marching in double precision.
    MarchingF64,
    /// Ray marching with the 3D distance map of Jeschke et al. 2007, sec. 4.4 (empty-space
    /// jumps of up to 31 cells; cells of at most 256 per axis and 32 height layers, or per
    /// voxel of an instanced object) in single precision.
    DistanceMapF32,
    /// Ray marching with the distance map in double precision.
    DistanceMapF64,
    /// Tetrahedral shells (Porumbescu et al. 2005: each prism split into three tetrahedra with
    /// consistent diagonals, a piecewise-linear map, sampled like marching) in single
    /// precision; height fields only.
    TetrahedraF32,
    /// Tetrahedral shells in double precision.
    TetrahedraF64,
    /// Projective displacement mapping (parallel offset prisms, world-space samples projected
    /// linearly to texture space, jittered first sample, no bottom-level structure) in single
    /// precision; height fields only.
    ProjectiveF32,
    /// Projective displacement mapping in double precision.
    ProjectiveF64,
    /// Cone tracing with silhouettes (Ouazzani Chahdi et al. 2021: conservative cone map,
    /// per-vertex quadrics, viewing-ray rectification, per prism) in single precision; height
    /// fields only.
    ConeRayF32,
    /// Cone tracing with viewing-ray rectification in double precision.
    ConeRayF64,
    /// Cone tracing with cone rectification (the paper's second correction) in single
    /// precision; height fields only.
    ConeConeF32,
    /// Cone tracing with cone rectification in double precision.
    ConeConeF64,
    /// Curved shell mapping (Jeschke et al. 2007, sec. 3.2 and 4.5: Coons patches over the
    /// vertex normals, height compression `w / 2 + 1 / 4`, heights by the interpolation of
    /// its Eq. 2, marched like [`Method::MarchingF32`]) in single precision; height fields
    /// only. A different surface: compared with [`Method::TessellatedCurved`].
    CurvedF32,
    /// Curved shell mapping in double precision.
    CurvedF64,
    /// The pre-tessellated microtriangles traced by Embree 3 (single precision): what users pick
    /// today, its kernels pinned to the instruction set this binary is built for (AVX2 for
    /// x86-64-v3), so that both sides use the same vector width. Only with the `embree` feature.
    EmbreeF32,
    /// [`Method::EmbreeF32`] with Embree choosing its kernels for this CPU (AVX-512 where the
    /// CPU has it). Only with the `embree` feature.
    EmbreeNativeF32,
    /// Pre-tessellated microtriangles in a world-space BVH (f64): the reference.
    Tessellated,
    /// The curved shell mapping's surface pre-tessellated (microtriangle vertices through the
    /// curved mapping, f64): the reference of [`Method::CurvedF32`] and [`Method::CurvedF64`].
    TessellatedCurved,
}

impl Method {
    /// All methods, references last.
    pub const ALL: [Method; 24] = [
        Method::NonlinearF32,
        Method::NonlinearF64,
        Method::AffineF32,
        Method::AffineF64,
        Method::GeometryImageF32,
        Method::GeometryImageF64,
        Method::MarchingF32,
        Method::MarchingF64,
        Method::DistanceMapF32,
        Method::DistanceMapF64,
        Method::TetrahedraF32,
        Method::TetrahedraF64,
        Method::ProjectiveF32,
        Method::ProjectiveF64,
        Method::ConeRayF32,
        Method::ConeRayF64,
        Method::ConeConeF32,
        Method::ConeConeF64,
        Method::CurvedF32,
        Method::CurvedF64,
        Method::EmbreeF32,
        Method::EmbreeNativeF32,
        Method::Tessellated,
        Method::TessellatedCurved,
    ];

    /// Short name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::NonlinearF32 => "nonlinear f32",
            Method::NonlinearF64 => "nonlinear f64",
            Method::AffineF32 => "tessellation-free f32",
            Method::AffineF64 => "tessellation-free f64",
            Method::GeometryImageF32 => "geometry image f32",
            Method::GeometryImageF64 => "geometry image f64",
            Method::MarchingF32 => "ray marching f32",
            Method::MarchingF64 => "ray marching f64",
            Method::DistanceMapF32 => "marching + distance map f32",
            Method::DistanceMapF64 => "marching + distance map f64",
            Method::TetrahedraF32 => "tetrahedra f32",
            Method::TetrahedraF64 => "tetrahedra f64",
            Method::ProjectiveF32 => "projective f32",
            Method::ProjectiveF64 => "projective f64",
            Method::ConeRayF32 => "cone tracing (ray rect.) f32",
            Method::ConeRayF64 => "cone tracing (ray rect.) f64",
            Method::ConeConeF32 => "cone tracing (cone rect.) f32",
            Method::ConeConeF64 => "cone tracing (cone rect.) f64",
            Method::CurvedF32 => "curved shell f32",
            Method::CurvedF64 => "curved shell f64",
            Method::EmbreeF32 => "Embree 3 pre-tessellated f32",
            Method::EmbreeNativeF32 => "Embree 3 pre-tessellated f32, native ISA",
            Method::Tessellated => "pre-tessellated f64",
            Method::TessellatedCurved => "pre-tessellated curved f64",
        }
    }

    /// File-name friendly name.
    #[must_use]
    pub fn slug(self) -> &'static str {
        match self {
            Method::NonlinearF32 => "nonlinear-f32",
            Method::NonlinearF64 => "nonlinear-f64",
            Method::AffineF32 => "tessellation-free-f32",
            Method::AffineF64 => "tessellation-free-f64",
            Method::GeometryImageF32 => "geometry-image-f32",
            Method::GeometryImageF64 => "geometry-image-f64",
            Method::MarchingF32 => "marching-f32",
            Method::MarchingF64 => "marching-f64",
            Method::DistanceMapF32 => "distance-map-f32",
            Method::DistanceMapF64 => "distance-map-f64",
            Method::TetrahedraF32 => "tetrahedra-f32",
            Method::TetrahedraF64 => "tetrahedra-f64",
            Method::ProjectiveF32 => "projective-f32",
            Method::ProjectiveF64 => "projective-f64",
            Method::ConeRayF32 => "cone-ray-f32",
            Method::ConeRayF64 => "cone-ray-f64",
            Method::ConeConeF32 => "cone-cone-f32",
            Method::ConeConeF64 => "cone-cone-f64",
            Method::CurvedF32 => "curved-f32",
            Method::CurvedF64 => "curved-f64",
            Method::EmbreeF32 => "embree-f32",
            Method::EmbreeNativeF32 => "embree-native-f32",
            Method::Tessellated => "tessellated-f64",
            Method::TessellatedCurved => "tessellated-curved-f64",
        }
    }

    /// The reference its error is measured against: the pre-tessellated surface it renders.
    #[must_use]
    pub fn reference(self) -> Method {
        match self {
            Method::CurvedF32 | Method::CurvedF64 | Method::TessellatedCurved => {
                Method::TessellatedCurved
            }
            _ => Method::Tessellated,
        }
    }

    /// Whether this is a pre-tessellated reference.
    #[must_use]
    pub fn is_reference(self) -> bool {
        matches!(self, Method::Tessellated | Method::TessellatedCurved)
    }

    /// The f64 run of the same surface, whose difference is this method's precision error
    /// alone (nonlinear f64; curved shell f64 for the curved methods).
    #[must_use]
    pub fn f64_partner(self) -> Method {
        match self {
            Method::CurvedF32 | Method::CurvedF64 | Method::TessellatedCurved => Method::CurvedF64,
            _ => Method::NonlinearF64,
        }
    }

    /// The method named `slug` (as [`Method::slug`] writes it).
    #[must_use]
    pub fn from_slug(slug: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.slug() == slug)
    }

    /// Whether the method can render `scene` (tessellation-free mapping handles height
    /// fields only, not instanced objects; geometry images also need one uv chart over the
    /// unit square with a power-of-two tiled map).
    #[must_use]
    pub fn supports(self, scene: &Scene) -> bool {
        self.unsupported_reason(scene).is_none()
    }

    /// Why the method cannot render `scene` (one of its objects), or `None` when it can.
    #[must_use]
    pub fn unsupported_reason(self, scene: &Scene) -> Option<&'static str> {
        scene
            .objects()
            .find_map(|object| self.unsupported_reason_for_object(object))
    }

    /// Why the method cannot render the object `scene` alone (its `others` not looked at),
    /// or `None` when it can.
    #[must_use]
    pub fn unsupported_reason_for_object(self, scene: &Scene) -> Option<&'static str> {
        match self {
            Method::AffineF32 | Method::AffineF64 => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "tessellation-free mapping renders height fields, not instanced objects",
                )
            }
            Method::GeometryImageF32 | Method::GeometryImageF64 => {
                crate::trace::geometry_image::unsupported_reason(scene)
            }
            Method::MarchingF32 | Method::MarchingF64 => None,
            Method::DistanceMapF32 | Method::DistanceMapF64 => match &scene.content {
                Content::Displacement(field) if field.square_side().is_none() => {
                    Some("distance maps are built for square maps with a power-of-two side")
                }
                _ => None,
            },
            Method::ProjectiveF32 | Method::ProjectiveF64 => {
                if !matches!(scene.content, Content::Displacement(_)) {
                    Some(
                        "projective displacement mapping renders height fields, not instanced objects",
                    )
                } else if scene.midlevel != 0.0 {
                    Some(
                        "projective displacement mapping offsets its own prisms from the base mesh: midlevel 0 only",
                    )
                } else {
                    None
                }
            }
            Method::TetrahedraF32 | Method::TetrahedraF64 => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "tetrahedral shells are implemented for height fields, not instanced objects",
                )
            }
            Method::ConeRayF32 | Method::ConeRayF64 | Method::ConeConeF32 | Method::ConeConeF64 => {
                match &scene.content {
                    Content::Shell(_) => {
                        Some("cone tracing renders height fields, not instanced objects")
                    }
                    Content::Displacement(field) if field.square_side().is_none() => {
                        Some("cone maps are built for square maps with a power-of-two side")
                    }
                    Content::Displacement(_) => None,
                }
            }
            Method::EmbreeF32 | Method::EmbreeNativeF32 => {
                if cfg!(feature = "embree") {
                    None
                } else {
                    Some(
                        "built without the `embree` feature (install libembree-dev, then \
                         `cargo run --release --features embree`)",
                    )
                }
            }
            Method::CurvedF32 | Method::CurvedF64 | Method::TessellatedCurved => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "curved shell mapping is implemented for height fields, not instanced objects",
                )
            }
            Method::NonlinearF32 | Method::NonlinearF64 | Method::Tessellated => None,
        }
    }

    /// Builds the method's acceleration data for `scene`; `None` when it does not support it.
    /// A scene of several objects gets each object's own data, traced as one
    /// ([`ObjectUnion`]).
    #[must_use]
    pub fn build(self, scene: &Scene) -> Option<Box<dyn Tracer>> {
        if !self.supports(scene) {
            return None;
        }
        if scene.others.is_empty() {
            return self.build_object(scene);
        }
        let parts = scene
            .objects()
            .map(|object| Some((self.build_object(object)?, object.triangles.len())))
            .collect::<Option<Vec<_>>>()?;
        Some(Box::new(ObjectUnion::new(parts)))
    }

    /// [`Method::build`] for the object `scene` alone (its `others` not looked at).
    fn build_object(self, scene: &Scene) -> Option<Box<dyn Tracer>> {
        Some(match self {
            Method::NonlinearF32 => Box::new(Nonlinear::<f32>::new(scene)),
            Method::NonlinearF64 => Box::new(Nonlinear::<f64>::new(scene)),
            Method::AffineF32 => Box::new(TessellationFree::<f32>::new(scene)?),
            Method::AffineF64 => Box::new(TessellationFree::<f64>::new(scene)?),
            Method::GeometryImageF32 => Box::new(GeometryImageTracer::<f32>::new(scene)?),
            Method::GeometryImageF64 => Box::new(GeometryImageTracer::<f64>::new(scene)?),
            Method::MarchingF32
            | Method::MarchingF64
            | Method::DistanceMapF32
            | Method::DistanceMapF64
                if matches!(scene.content, Content::Shell(_)) =>
            {
                let jumps = matches!(self, Method::DistanceMapF32 | Method::DistanceMapF64);
                if self.name().ends_with("f32") {
                    Box::new(VolumeMarching::<f32>::new(scene, jumps)?)
                } else {
                    Box::new(VolumeMarching::<f64>::new(scene, jumps)?)
                }
            }
            Method::MarchingF32 => Box::new(Marching::<f32>::new(scene)?),
            Method::MarchingF64 => Box::new(Marching::<f64>::new(scene)?),
            Method::DistanceMapF32 => Box::new(Marching::<f32>::distance_map(scene)?),
            Method::DistanceMapF64 => Box::new(Marching::<f64>::distance_map(scene)?),
            Method::TetrahedraF32 => Box::new(Marching::<f32>::tetrahedra(scene)?),
            Method::TetrahedraF64 => Box::new(Marching::<f64>::tetrahedra(scene)?),
            Method::ProjectiveF32 => Box::new(Projective::<f32>::new(scene)?),
            Method::ProjectiveF64 => Box::new(Projective::<f64>::new(scene)?),
            Method::ConeRayF32 => Box::new(ConeTracer::<f32>::new(scene, Rectification::Ray)?),
            Method::ConeRayF64 => Box::new(ConeTracer::<f64>::new(scene, Rectification::Ray)?),
            Method::ConeConeF32 => Box::new(ConeTracer::<f32>::new(scene, Rectification::Cone)?),
            Method::ConeConeF64 => Box::new(ConeTracer::<f64>::new(scene, Rectification::Cone)?),
            Method::CurvedF32 => Box::new(Marching::<f32>::curved(scene)?),
            Method::CurvedF64 => Box::new(Marching::<f64>::curved(scene)?),
            #[cfg(feature = "embree")]
            Method::EmbreeF32 => Box::new(crate::trace::embree_reference::EmbreeTessellated::new(
                scene,
                crate::trace::embree_reference::Isa::Build,
            )?),
            #[cfg(feature = "embree")]
            Method::EmbreeNativeF32 => {
                Box::new(crate::trace::embree_reference::EmbreeTessellated::new(
                    scene,
                    crate::trace::embree_reference::Isa::Native,
                )?)
            }
            #[cfg(not(feature = "embree"))]
            Method::EmbreeF32 | Method::EmbreeNativeF32 => return None,
            Method::Tessellated => Box::new(Tessellated::new(scene)),
            Method::TessellatedCurved => Box::new(Tessellated::curved(scene)),
        })
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
