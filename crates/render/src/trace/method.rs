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

/// The arithmetic a method traces in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Precision {
    /// Single precision.
    F32,
    /// Double precision.
    F64,
}

impl Precision {
    /// `"f32"` or `"f64"`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F64 => "f64",
        }
    }
}

/// A family of methods: one algorithm, in the precisions [`Method::new`] accepts for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Kind {
    /// Nonlinear ray tracing (Ogaki 2023).
    Nonlinear,
    /// Tessellation-free displacement mapping (Thonat et al. 2021); height fields only.
    TessellationFree,
    /// Geometry-image ray tracing (Carr et al. 2006); height fields on one uv chart only.
    GeometryImage,
    /// Smooth shell mapping by ray marching (Jeschke et al. 2007); instanced objects voxelised.
    Marching,
    /// Ray marching with Jeschke's 3D distance map (sec. 4.4); instanced objects voxelised.
    DistanceMap,
    /// Tetrahedral shells (piecewise-linear mapping); height fields only.
    Tetrahedra,
    /// Projective displacement mapping (parallel offset prisms); height fields only.
    Projective,
    /// Cone tracing with silhouettes, viewing-ray rectification (Ouazzani Chahdi et al. 2021);
    /// height fields only.
    ConeRay,
    /// Cone tracing with silhouettes, cone rectification; height fields only.
    ConeCone,
    /// Curved shell mapping (Jeschke et al. 2007, Coons patches); height fields only.
    Curved,
    /// The pre-tessellated microtriangles through Embree 3, pinned to the build's instruction
    /// set (f32; the `embree` feature).
    Embree,
    /// Embree 3 choosing its kernels for this CPU (f32; the `embree` feature).
    EmbreeNative,
    /// The same microtriangles as Embree 3 grid geometry (one vertex per texel corner),
    /// pinned to the build's instruction set (f32; the `embree` feature); height fields whose
    /// base mesh pairs triangles into squares of whole texels only.
    EmbreeGrid,
    /// The pre-tessellated reference (f64).
    Tessellated,
    /// The curved shell's surface pre-tessellated (f64): the curved shell's reference.
    TessellatedCurved,
}

/// A way of intersecting rays with a scene's displaced surface: a [`Kind`] in a [`Precision`].
/// The methods that exist are the constants below ([`Method::ALL`]); [`Method::new`] finds
/// one by kind and precision.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Method {
    kind: Kind,
    precision: Precision,
}

/// Per method: its display name, its slug (`--methods`, file names) and what it is.
struct Entry {
    method: Method,
    name: &'static str,
    slug: &'static str,
}

/// The one table of the methods' names, in [`Method::ALL`]'s order.
const TABLE: [Entry; 25] = [
    Entry {
        method: Method::NONLINEAR_F32,
        name: "nonlinear f32",
        slug: "nonlinear-f32",
    },
    Entry {
        method: Method::NONLINEAR_F64,
        name: "nonlinear f64",
        slug: "nonlinear-f64",
    },
    Entry {
        method: Method::TESSELLATION_FREE_F32,
        name: "tessellation-free f32",
        slug: "tessellation-free-f32",
    },
    Entry {
        method: Method::TESSELLATION_FREE_F64,
        name: "tessellation-free f64",
        slug: "tessellation-free-f64",
    },
    Entry {
        method: Method::GEOMETRY_IMAGE_F32,
        name: "geometry image f32",
        slug: "geometry-image-f32",
    },
    Entry {
        method: Method::GEOMETRY_IMAGE_F64,
        name: "geometry image f64",
        slug: "geometry-image-f64",
    },
    Entry {
        method: Method::MARCHING_F32,
        name: "ray marching f32",
        slug: "marching-f32",
    },
    Entry {
        method: Method::MARCHING_F64,
        name: "ray marching f64",
        slug: "marching-f64",
    },
    Entry {
        method: Method::DISTANCE_MAP_F32,
        name: "marching + distance map f32",
        slug: "distance-map-f32",
    },
    Entry {
        method: Method::DISTANCE_MAP_F64,
        name: "marching + distance map f64",
        slug: "distance-map-f64",
    },
    Entry {
        method: Method::TETRAHEDRA_F32,
        name: "tetrahedra f32",
        slug: "tetrahedra-f32",
    },
    Entry {
        method: Method::TETRAHEDRA_F64,
        name: "tetrahedra f64",
        slug: "tetrahedra-f64",
    },
    Entry {
        method: Method::PROJECTIVE_F32,
        name: "projective f32",
        slug: "projective-f32",
    },
    Entry {
        method: Method::PROJECTIVE_F64,
        name: "projective f64",
        slug: "projective-f64",
    },
    Entry {
        method: Method::CONE_RAY_F32,
        name: "cone tracing (ray rect.) f32",
        slug: "cone-ray-f32",
    },
    Entry {
        method: Method::CONE_RAY_F64,
        name: "cone tracing (ray rect.) f64",
        slug: "cone-ray-f64",
    },
    Entry {
        method: Method::CONE_CONE_F32,
        name: "cone tracing (cone rect.) f32",
        slug: "cone-cone-f32",
    },
    Entry {
        method: Method::CONE_CONE_F64,
        name: "cone tracing (cone rect.) f64",
        slug: "cone-cone-f64",
    },
    Entry {
        method: Method::CURVED_F32,
        name: "curved shell f32",
        slug: "curved-f32",
    },
    Entry {
        method: Method::CURVED_F64,
        name: "curved shell f64",
        slug: "curved-f64",
    },
    Entry {
        method: Method::EMBREE_F32,
        name: "Embree 3 pre-tessellated f32",
        slug: "embree-f32",
    },
    Entry {
        method: Method::EMBREE_NATIVE_F32,
        name: "Embree 3 pre-tessellated f32, native ISA",
        slug: "embree-native-f32",
    },
    Entry {
        method: Method::EMBREE_GRID_F32,
        name: "Embree 3 grids f32",
        slug: "embree-grid-f32",
    },
    Entry {
        method: Method::TESSELLATED_F64,
        name: "pre-tessellated f64",
        slug: "tessellated-f64",
    },
    Entry {
        method: Method::TESSELLATED_CURVED_F64,
        name: "pre-tessellated curved f64",
        slug: "tessellated-curved-f64",
    },
];

impl Method {
    /// Nonlinear ray tracing in single precision.
    pub const NONLINEAR_F32: Method = Method {
        kind: Kind::Nonlinear,
        precision: Precision::F32,
    };
    /// Nonlinear ray tracing in double precision.
    pub const NONLINEAR_F64: Method = Method {
        kind: Kind::Nonlinear,
        precision: Precision::F64,
    };
    /// Tessellation-free displacement mapping (Thonat et al. 2021: world-space node boxes by
    /// affine arithmetic, flat world microtriangles) in single precision; displacement only.
    pub const TESSELLATION_FREE_F32: Method = Method {
        kind: Kind::TessellationFree,
        precision: Precision::F32,
    };
    /// Tessellation-free displacement mapping in double precision; displacement only.
    pub const TESSELLATION_FREE_F64: Method = Method {
        kind: Kind::TessellationFree,
        precision: Precision::F64,
    };
    /// Geometry-image ray tracing (Carr et al. 2006: the displaced surface re-sampled on the
    /// texel grid, a min-max pyramid of world boxes walked by hit/miss links) in single
    /// precision; height fields on one uv chart only.
    pub const GEOMETRY_IMAGE_F32: Method = Method {
        kind: Kind::GeometryImage,
        precision: Precision::F32,
    };
    /// Geometry-image ray tracing in double precision.
    pub const GEOMETRY_IMAGE_F64: Method = Method {
        kind: Kind::GeometryImage,
        precision: Precision::F64,
    };
    /// Smooth shell mapping by ray marching (Jeschke et al. 2007: canonical-space sampling with
    /// image-space error correction, 2 samples per texel, binary-search refinement) in single
    /// precision; instanced objects are voxelised in their tile (its 3D textures).
    pub const MARCHING_F32: Method = Method {
        kind: Kind::Marching,
        precision: Precision::F32,
    };
    /// Smooth shell mapping by ray marching in double precision.
    pub const MARCHING_F64: Method = Method {
        kind: Kind::Marching,
        precision: Precision::F64,
    };
    /// Ray marching with the 3D distance map of Jeschke et al. 2007, sec. 4.4 (empty-space
    /// jumps of up to 31 cells; cells of at most 256 per axis and 32 height layers, or per
    /// voxel of an instanced object) in single precision.
    pub const DISTANCE_MAP_F32: Method = Method {
        kind: Kind::DistanceMap,
        precision: Precision::F32,
    };
    /// Ray marching with the distance map in double precision.
    pub const DISTANCE_MAP_F64: Method = Method {
        kind: Kind::DistanceMap,
        precision: Precision::F64,
    };
    /// Tetrahedral shells (Porumbescu et al. 2005: each prism split into three tetrahedra with
    /// consistent diagonals, a piecewise-linear map, sampled like marching) in single
    /// precision; height fields only.
    pub const TETRAHEDRA_F32: Method = Method {
        kind: Kind::Tetrahedra,
        precision: Precision::F32,
    };
    /// Tetrahedral shells in double precision.
    pub const TETRAHEDRA_F64: Method = Method {
        kind: Kind::Tetrahedra,
        precision: Precision::F64,
    };
    /// Projective displacement mapping (parallel offset prisms, world-space samples projected
    /// linearly to texture space, jittered first sample, no bottom-level structure) in single
    /// precision; height fields only.
    pub const PROJECTIVE_F32: Method = Method {
        kind: Kind::Projective,
        precision: Precision::F32,
    };
    /// Projective displacement mapping in double precision.
    pub const PROJECTIVE_F64: Method = Method {
        kind: Kind::Projective,
        precision: Precision::F64,
    };
    /// Cone tracing with silhouettes (Ouazzani Chahdi et al. 2021: conservative cone map, per-
    /// vertex quadrics, viewing-ray rectification, per prism) in single precision; height
    /// fields only.
    pub const CONE_RAY_F32: Method = Method {
        kind: Kind::ConeRay,
        precision: Precision::F32,
    };
    /// Cone tracing with viewing-ray rectification in double precision.
    pub const CONE_RAY_F64: Method = Method {
        kind: Kind::ConeRay,
        precision: Precision::F64,
    };
    /// Cone tracing with cone rectification (the paper's second correction) in single
    /// precision; height fields only.
    pub const CONE_CONE_F32: Method = Method {
        kind: Kind::ConeCone,
        precision: Precision::F32,
    };
    /// Cone tracing with cone rectification in double precision.
    pub const CONE_CONE_F64: Method = Method {
        kind: Kind::ConeCone,
        precision: Precision::F64,
    };
    /// Curved shell mapping (Jeschke et al. 2007, sec. 3.2 and 4.5: Coons patches over the
    /// vertex normals, height compression `w / 2 + 1 / 4`, heights by the interpolation of its
    /// Eq. 2, marched like [`Method::MARCHING_F32`]) in single precision; height fields only. A
    /// different surface: compared with [`Method::TESSELLATED_CURVED_F64`].
    pub const CURVED_F32: Method = Method {
        kind: Kind::Curved,
        precision: Precision::F32,
    };
    /// Curved shell mapping in double precision.
    pub const CURVED_F64: Method = Method {
        kind: Kind::Curved,
        precision: Precision::F64,
    };
    /// The pre-tessellated microtriangles traced by Embree 3 (single precision): what users
    /// pick today, its kernels pinned to the instruction set this binary is built for (AVX2 for
    /// x86-64-v3), so that both sides use the same vector width. Only with the `embree`
    /// feature.
    pub const EMBREE_F32: Method = Method {
        kind: Kind::Embree,
        precision: Precision::F32,
    };
    /// [`Method::EMBREE_F32`] with Embree choosing its kernels for this CPU (AVX-512 where the
    /// CPU has it). Only with the `embree` feature.
    pub const EMBREE_NATIVE_F32: Method = Method {
        kind: Kind::EmbreeNative,
        precision: Precision::F32,
    };
    /// The same microtriangles as Embree 3 grid geometry, one vertex per texel corner
    /// (`RTC_GEOMETRY_TYPE_GRID`; [`crate::trace::grid_mesh`]), kernels pinned as
    /// [`Method::EMBREE_F32`]'s: what a memory-conscious Embree user builds for a height
    /// field. Only with the `embree` feature, for base meshes of texel squares.
    pub const EMBREE_GRID_F32: Method = Method {
        kind: Kind::EmbreeGrid,
        precision: Precision::F32,
    };
    /// Pre-tessellated microtriangles in a world-space BVH (f64): the reference.
    pub const TESSELLATED_F64: Method = Method {
        kind: Kind::Tessellated,
        precision: Precision::F64,
    };
    /// The curved shell mapping's surface pre-tessellated (microtriangle vertices through the
    /// curved mapping, f64): the reference of [`Method::CURVED_F32`] and [`Method::CURVED_F64`].
    pub const TESSELLATED_CURVED_F64: Method = Method {
        kind: Kind::TessellatedCurved,
        precision: Precision::F64,
    };

    /// All methods, references last.
    pub const ALL: [Method; 25] = [
        Method::NONLINEAR_F32,
        Method::NONLINEAR_F64,
        Method::TESSELLATION_FREE_F32,
        Method::TESSELLATION_FREE_F64,
        Method::GEOMETRY_IMAGE_F32,
        Method::GEOMETRY_IMAGE_F64,
        Method::MARCHING_F32,
        Method::MARCHING_F64,
        Method::DISTANCE_MAP_F32,
        Method::DISTANCE_MAP_F64,
        Method::TETRAHEDRA_F32,
        Method::TETRAHEDRA_F64,
        Method::PROJECTIVE_F32,
        Method::PROJECTIVE_F64,
        Method::CONE_RAY_F32,
        Method::CONE_RAY_F64,
        Method::CONE_CONE_F32,
        Method::CONE_CONE_F64,
        Method::CURVED_F32,
        Method::CURVED_F64,
        Method::EMBREE_F32,
        Method::EMBREE_NATIVE_F32,
        Method::EMBREE_GRID_F32,
        Method::TESSELLATED_F64,
        Method::TESSELLATED_CURVED_F64,
    ];

    /// The method of `kind` in `precision`, if it exists (Embree runs in f32 only, the
    /// references in f64 only).
    #[must_use]
    pub fn new(kind: Kind, precision: Precision) -> Option<Method> {
        let method = Method { kind, precision };
        Self::ALL.contains(&method).then_some(method)
    }

    /// The method of `kind` in `precision`, or in the one precision the kind has.
    #[must_use]
    pub fn in_precision_or_only(kind: Kind, precision: Precision) -> Method {
        Self::new(kind, precision).unwrap_or(Method {
            kind,
            precision: match precision {
                Precision::F32 => Precision::F64,
                Precision::F64 => Precision::F32,
            },
        })
    }

    /// Its kind.
    #[must_use]
    pub fn kind(self) -> Kind {
        self.kind
    }

    /// Its precision.
    #[must_use]
    pub fn precision(self) -> Precision {
        self.precision
    }

    fn entry(self) -> &'static Entry {
        // Every `Method` is one of the table's: the fields are private, and `new` checks.
        let found = TABLE.iter().find(|e| e.method == self);
        found.unwrap_or(&TABLE[0])
    }

    /// Short name.
    #[must_use]
    pub fn name(self) -> &'static str {
        self.entry().name
    }

    /// File-name friendly name.
    #[must_use]
    pub fn slug(self) -> &'static str {
        self.entry().slug
    }

    /// The reference its error is measured against: the pre-tessellated surface it renders.
    #[must_use]
    pub fn reference(self) -> Method {
        match self {
            Method::CURVED_F32 | Method::CURVED_F64 | Method::TESSELLATED_CURVED_F64 => {
                Method::TESSELLATED_CURVED_F64
            }
            _ => Method::TESSELLATED_F64,
        }
    }

    /// Whether this is a pre-tessellated reference.
    #[must_use]
    pub fn is_reference(self) -> bool {
        matches!(
            self,
            Method::TESSELLATED_F64 | Method::TESSELLATED_CURVED_F64
        )
    }

    /// The f64 run of the same surface, whose difference is this method's precision error
    /// alone (nonlinear f64; curved shell f64 for the curved methods).
    #[must_use]
    pub fn f64_partner(self) -> Method {
        match self {
            Method::CURVED_F32 | Method::CURVED_F64 | Method::TESSELLATED_CURVED_F64 => {
                Method::CURVED_F64
            }
            _ => Method::NONLINEAR_F64,
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
        match self.kind {
            Kind::TessellationFree => (!matches!(scene.content, Content::Displacement(_)))
                .then_some(
                    "tessellation-free mapping renders height fields, not instanced objects",
                ),
            Kind::GeometryImage => crate::trace::geometry_image::unsupported_reason(scene),
            Kind::Marching => None,
            Kind::DistanceMap => match &scene.content {
                Content::Displacement(field) if field.square_side().is_none() => {
                    Some("distance maps are built for square maps with a power-of-two side")
                }
                _ => None,
            },
            Kind::Projective => {
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
            Kind::Tetrahedra => (!matches!(scene.content, Content::Displacement(_))).then_some(
                "tetrahedral shells are implemented for height fields, not instanced objects",
            ),
            Kind::ConeRay | Kind::ConeCone => match &scene.content {
                Content::Shell(_) => {
                    Some("cone tracing renders height fields, not instanced objects")
                }
                Content::Displacement(field) if field.square_side().is_none() => {
                    Some("cone maps are built for square maps with a power-of-two side")
                }
                Content::Displacement(_) => None,
            },
            Kind::EmbreeGrid if cfg!(feature = "embree") => {
                crate::trace::grid_mesh::squares(scene).err()
            }
            Kind::Embree | Kind::EmbreeNative | Kind::EmbreeGrid => {
                if cfg!(feature = "embree") {
                    None
                } else {
                    Some(
                        "built without the `embree` feature (install libembree-dev, then \
                         `cargo run --release --features embree`)",
                    )
                }
            }
            Kind::Curved | Kind::TessellatedCurved => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "curved shell mapping is implemented for height fields, not instanced objects",
                )
            }
            Kind::Nonlinear | Kind::Tessellated => None,
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
        Some(match (self.kind, self.precision) {
            (Kind::Nonlinear, Precision::F32) => Box::new(Nonlinear::<f32>::new(scene)),
            (Kind::Nonlinear, Precision::F64) => Box::new(Nonlinear::<f64>::new(scene)),
            (Kind::TessellationFree, Precision::F32) => {
                Box::new(TessellationFree::<f32>::new(scene)?)
            }
            (Kind::TessellationFree, Precision::F64) => {
                Box::new(TessellationFree::<f64>::new(scene)?)
            }
            (Kind::GeometryImage, Precision::F32) => {
                Box::new(GeometryImageTracer::<f32>::new(scene)?)
            }
            (Kind::GeometryImage, Precision::F64) => {
                Box::new(GeometryImageTracer::<f64>::new(scene)?)
            }
            (Kind::Marching, Precision::F32)
            | (Kind::Marching, Precision::F64)
            | (Kind::DistanceMap, Precision::F32)
            | (Kind::DistanceMap, Precision::F64)
                if matches!(scene.content, Content::Shell(_)) =>
            {
                let jumps = self.kind == Kind::DistanceMap;
                if self.precision == Precision::F32 {
                    Box::new(VolumeMarching::<f32>::new(scene, jumps)?)
                } else {
                    Box::new(VolumeMarching::<f64>::new(scene, jumps)?)
                }
            }
            (Kind::Marching, Precision::F32) => Box::new(Marching::<f32>::new(scene)?),
            (Kind::Marching, Precision::F64) => Box::new(Marching::<f64>::new(scene)?),
            (Kind::DistanceMap, Precision::F32) => Box::new(Marching::<f32>::distance_map(scene)?),
            (Kind::DistanceMap, Precision::F64) => Box::new(Marching::<f64>::distance_map(scene)?),
            (Kind::Tetrahedra, Precision::F32) => Box::new(Marching::<f32>::tetrahedra(scene)?),
            (Kind::Tetrahedra, Precision::F64) => Box::new(Marching::<f64>::tetrahedra(scene)?),
            (Kind::Projective, Precision::F32) => Box::new(Projective::<f32>::new(scene)?),
            (Kind::Projective, Precision::F64) => Box::new(Projective::<f64>::new(scene)?),
            (Kind::ConeRay, Precision::F32) => {
                Box::new(ConeTracer::<f32>::new(scene, Rectification::Ray)?)
            }
            (Kind::ConeRay, Precision::F64) => {
                Box::new(ConeTracer::<f64>::new(scene, Rectification::Ray)?)
            }
            (Kind::ConeCone, Precision::F32) => {
                Box::new(ConeTracer::<f32>::new(scene, Rectification::Cone)?)
            }
            (Kind::ConeCone, Precision::F64) => {
                Box::new(ConeTracer::<f64>::new(scene, Rectification::Cone)?)
            }
            (Kind::Curved, Precision::F32) => Box::new(Marching::<f32>::curved(scene)?),
            (Kind::Curved, Precision::F64) => Box::new(Marching::<f64>::curved(scene)?),
            #[cfg(feature = "embree")]
            (Kind::Embree, Precision::F32) => {
                Box::new(crate::trace::embree_reference::EmbreeTessellated::new(
                    scene,
                    crate::trace::embree_reference::Isa::Build,
                )?)
            }
            #[cfg(feature = "embree")]
            (Kind::EmbreeNative, Precision::F32) => {
                Box::new(crate::trace::embree_reference::EmbreeTessellated::new(
                    scene,
                    crate::trace::embree_reference::Isa::Native,
                )?)
            }
            #[cfg(feature = "embree")]
            (Kind::EmbreeGrid, Precision::F32) => {
                Box::new(crate::trace::embree_grid::EmbreeGrids::new(
                    scene,
                    crate::trace::embree_reference::Isa::Build,
                )?)
            }
            #[cfg(not(feature = "embree"))]
            (Kind::Embree | Kind::EmbreeNative | Kind::EmbreeGrid, Precision::F32) => return None,
            (Kind::Tessellated, Precision::F64) => Box::new(Tessellated::new(scene)),
            (Kind::TessellatedCurved, Precision::F64) => Box::new(Tessellated::curved(scene)),
            // No other combination is a method (`Method::new`).
            _ => return None,
        })
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::{Kind, Method, Precision};
    use clap::ValueEnum;

    /// One table names every method once; `new` finds exactly the methods of `ALL`, and a
    /// method's names end in its precision.
    #[test]
    fn every_method_has_one_name_and_one_kind_and_precision() {
        let mut slugs: Vec<&str> = Method::ALL.iter().map(|m| m.slug()).collect();
        let mut names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
        slugs.sort_unstable();
        slugs.dedup();
        names.sort_unstable();
        names.dedup();
        assert_eq!((slugs.len(), names.len()), (25, 25));
        let mut found = 0;
        for &kind in Kind::value_variants() {
            for precision in [Precision::F32, Precision::F64] {
                if let Some(m) = Method::new(kind, precision) {
                    found += 1;
                    assert_eq!((m.kind(), m.precision()), (kind, precision));
                    assert!(m.slug().ends_with(precision.name()), "{}", m.slug());
                    assert!(m.name().contains(precision.name()), "{}", m.name());
                    assert_eq!(Method::from_slug(m.slug()), Some(m));
                } else {
                    let only = Method::in_precision_or_only(kind, precision);
                    assert!(Method::ALL.contains(&only), "{kind:?}");
                    assert_ne!(only.precision(), precision);
                }
            }
        }
        assert_eq!(found, Method::ALL.len());
    }
}
