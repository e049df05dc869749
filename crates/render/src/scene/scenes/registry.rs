//! The built-in scenes by name: one registry ([`BUILTIN`]) of names, tags and builders, the
//! sizes, and `builtin`.

use super::paper::*;
use super::scene::*;
use super::variants::*;
use nlrt_poly::glam::DVec3;

/// What a built-in scene is for: the tags of the registry ([`BUILTIN`]), which the commands
/// select by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tag {
    /// Rendered by the default report and `nlrt bench` without names: the paper's displacement
    /// scenes (mountain, cylinder, fur), its Fig. 8 torus, the shell scenes and its Fig. 9.
    Report,
    /// Made for one measurement, not in the default report's renders; usable everywhere a
    /// scene is.
    Variant,
    /// Judged by the report's watertightness section (a closed mesh, or the mountain's convex
    /// shell, so that rays are decidable).
    ReportJudged,
    /// Meant for `nlrt watertight` (its rays are decidable, or aimed at a shell's object).
    Watertight,
    /// A ghost-hit torus ([`ghost_torus`]): spikes, tilt or twist where f32 once reported hits
    /// in front of the surface.
    Ghost,
    /// A uv-seam scene ([`seam_cube`], [`seam_sphere`]): the atlas is cut, so the two sides of
    /// a seam sample different texels.
    Seam,
    /// A coarse torus ([`COARSE_TORI`]): few base triangles, tall spikes beside plateaus.
    Coarse,
    /// Shell mapping of an instanced object (the others are displacement mapping).
    Shell,
}

/// One built-in scene: its name, its tags and how it is built at a [`Size`].
pub struct Builtin {
    /// Name (`nlrt render <name>`).
    pub name: &'static str,
    /// What it is for.
    pub tags: &'static [Tag],
    build: fn(Size) -> Option<Scene>,
}

impl Builtin {
    /// Whether it carries `tag`.
    #[must_use]
    pub fn has(&self, tag: Tag) -> bool {
        self.tags.contains(&tag)
    }
}

/// The mountain seen at grazing angles: just above the shell's top, over the map's edge,
/// looking across it about 4 degrees down.
fn mountain_grazing(size: Size) -> Scene {
    let mut m = mountain(size.pick(4096, 1024));
    m.name = "mountain-grazing";
    m.camera.eye = DVec3::new(0.0, 0.4, 0.95);
    m.camera.target = DVec3::new(0.0, 0.25, -1.0);
    m
}

/// The plateau seen at grazing angles: just above its top, looking across the plateau and
/// over its rim, down the far flank, about 8 degrees down.
fn plateau_grazing(size: Size) -> Scene {
    let mut p = plateau(size.pick(1024, 256));
    p.name = "plateau-grazing";
    p.camera.eye = DVec3::new(-0.3, 0.2, -0.2);
    p.camera.target = DVec3::new(1.0, 0.0, 0.9);
    p
}

/// `scene` with midlevel 0.5 (its map pushes in and out), renamed.
fn at_half_midlevel(mut scene: Scene, name: &'static str) -> Scene {
    scene.name = name;
    scene.midlevel = 0.5;
    scene
}

/// Coarse torus `k` of [`COARSE_TORI`].
fn coarse(k: usize, size: Size) -> Option<Scene> {
    let (name, shape) = COARSE_TORI[k];
    Some(coarse_torus(name, shape, size.pick(256, 64)))
}

use Tag::{Coarse, Ghost, Report, ReportJudged, Seam, Shell, Variant, Watertight};

/// Every built-in scene, the report's first (in the order it renders them), then the variants.
pub const BUILTIN: [Builtin; 32] = [
    Builtin {
        name: "mountain",
        tags: &[Report, ReportJudged, Watertight],
        build: |s| Some(mountain(s.pick(4096, 1024))),
    },
    Builtin {
        name: "cylinder",
        tags: &[Report, Watertight],
        build: |s| Some(cylinder(s.pick(4096, 1024))),
    },
    Builtin {
        name: "fur",
        tags: &[Report, ReportJudged, Watertight],
        build: |s| Some(fur(s.pick(256, 64))),
    },
    Builtin {
        name: "torus",
        tags: &[Report, ReportJudged, Watertight],
        build: |s| Some(torus_scene(s.pick(1024, 256))),
    },
    Builtin {
        name: "feathers",
        tags: &[Report, Watertight, Shell],
        build: |_| Some(feathers()),
    },
    Builtin {
        name: "scales",
        tags: &[Report, Watertight, Shell],
        build: |_| Some(scales()),
    },
    Builtin {
        name: "cornell",
        tags: &[Report, Watertight, Shell],
        build: |s| Some(cornell(s.detail(15, 6))),
    },
    Builtin {
        name: "highpoly",
        tags: &[Report, Watertight, Shell],
        build: |s| Some(highpoly(s.detail(270, 32))),
    },
    Builtin {
        name: "fig9",
        tags: &[Report, Watertight, Shell],
        build: |_| Some(fig9()),
    },
    Builtin {
        name: "dem-crop",
        tags: &[Variant],
        build: |s| Some(dem_crop(if s == Size::Small { 150 } else { 601 })),
    },
    Builtin {
        name: "mountain-midlevel",
        tags: &[Variant],
        build: |s| {
            Some(at_half_midlevel(
                mountain(s.pick(4096, 1024)),
                "mountain-midlevel",
            ))
        },
    },
    Builtin {
        name: "torus-midlevel",
        tags: &[Variant],
        build: |s| {
            Some(at_half_midlevel(
                torus_scene(s.pick(1024, 256)),
                "torus-midlevel",
            ))
        },
    },
    Builtin {
        name: COARSE_TORI[0].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(0, s),
    },
    Builtin {
        name: COARSE_TORI[1].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(1, s),
    },
    Builtin {
        name: COARSE_TORI[2].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(2, s),
    },
    Builtin {
        name: COARSE_TORI[3].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(3, s),
    },
    Builtin {
        name: COARSE_TORI[4].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(4, s),
    },
    Builtin {
        name: COARSE_TORI[5].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(5, s),
    },
    Builtin {
        name: COARSE_TORI[6].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(6, s),
    },
    Builtin {
        name: COARSE_TORI[7].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(7, s),
    },
    Builtin {
        name: COARSE_TORI[8].0,
        tags: &[Variant, Coarse, Watertight],
        build: |s| coarse(8, s),
    },
    Builtin {
        name: "mountain-grazing",
        tags: &[Variant, ReportJudged, Watertight],
        build: |s| Some(mountain_grazing(s)),
    },
    Builtin {
        name: "fur-cones",
        tags: &[Variant, Watertight],
        build: |s| Some(fur_cones(s.pick(256, 64))),
    },
    Builtin {
        name: "fig9-displaced",
        tags: &[Variant, ReportJudged, Watertight],
        build: |s| Some(fig9_displaced(s.pick(1024, 256))),
    },
    Builtin {
        name: "torus-spikes",
        tags: &[Variant, Ghost, Watertight],
        build: |s| ghost_torus("torus-spikes", s.pick(256, 64)),
    },
    Builtin {
        name: "torus-tilted",
        tags: &[Variant, Ghost, Watertight],
        build: |s| ghost_torus("torus-tilted", s.pick(256, 64)),
    },
    Builtin {
        name: "torus-twisted",
        tags: &[Variant, Ghost, Watertight],
        build: |s| ghost_torus("torus-twisted", s.pick(256, 64)),
    },
    Builtin {
        name: "plateau",
        tags: &[Variant, ReportJudged, Watertight],
        build: |s| Some(plateau(s.pick(1024, 256))),
    },
    Builtin {
        name: "plateau-grazing",
        tags: &[Variant, Watertight],
        build: |s| Some(plateau_grazing(s)),
    },
    Builtin {
        name: "cornell-floor",
        tags: &[Variant, Watertight, Shell],
        build: |s| Some(cornell_floor(s.detail(15, 6))),
    },
    Builtin {
        name: "seam-cube",
        tags: &[Variant, Seam, ReportJudged, Watertight],
        build: |s| Some(seam_cube(s.pick(1024, 256))),
    },
    Builtin {
        name: "seam-sphere",
        tags: &[Variant, Seam, Watertight],
        build: |s| Some(seam_sphere(s.pick(1024, 256))),
    },
];

/// The names of the built-in scenes carrying `tag`, in [`BUILTIN`]'s order.
#[must_use]
pub fn names(tag: Tag) -> Vec<&'static str> {
    BUILTIN
        .iter()
        .filter(|b| b.has(tag))
        .map(|b| b.name)
        .collect()
}

/// Whether `name` is a built-in scene.
#[must_use]
pub fn is_builtin(name: &str) -> bool {
    BUILTIN.iter().any(|b| b.name == name)
}

/// Sizes of a built-in scene: the paper's, or reduced for quick runs, or the paper's with
/// every height map of a chosen side (a scale sweep).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// The paper's sizes (4096^2 maps; the fur's 256^2 spikes tiled 8 x 8).
    Paper,
    /// Maps a quarter of the side (the fur's 64^2), same meshes.
    Small,
    /// The paper's sizes, with every height map of this side (a power of two, at least
    /// [`MIN_MAP_SIDE`]: see [`Size::map_side`]); the same terrain or relief, sampled finer or
    /// coarser.
    MapSide(usize),
}

/// The smallest map side [`Size::map_side`] accepts: the fBm maps' coarsest noise period is
/// 4 lattice cells across the map, and the finest octave of 8 needs at least one sample per
/// cell of period `4 * 2^7 = 512`.
pub const MIN_MAP_SIDE: usize = 512;

impl Size {
    /// [`Size::MapSide`] after checking `side`: a power of two from [`MIN_MAP_SIDE`] to the
    /// scene files' largest map (16384).
    ///
    /// # Errors
    /// A side outside that range or not a power of two, with a message saying so.
    pub fn map_side(side: usize) -> Result<Self, String> {
        if side.is_power_of_two() && (MIN_MAP_SIDE..=16384).contains(&side) {
            Ok(Self::MapSide(side))
        } else {
            Err(format!(
                "map side {side} must be a power of two from {MIN_MAP_SIDE} to 16384"
            ))
        }
    }

    /// The side to use for a map whose paper size is `paper` and small size `small`.
    #[must_use]
    fn pick(self, paper: usize, small: usize) -> usize {
        match self {
            Self::Paper => paper,
            Self::Small => small,
            Self::MapSide(side) => side,
        }
    }

    /// An object resolution or other non-map size: the map side does not change it.
    #[must_use]
    fn detail(self, paper: usize, small: usize) -> usize {
        if self == Self::Small { small } else { paper }
    }
}

/// The built-in scene `name` at `size`; `None` for an unknown name.
#[must_use]
pub fn builtin(name: &str, size: Size) -> Option<Scene> {
    BUILTIN
        .iter()
        .find(|b| b.name == name)
        .and_then(|b| (b.build)(size))
}
