//! The built-in scenes by name: the lists the commands iterate, the sizes, and `builtin`.

use super::paper::*;
use super::scene::*;
use super::variants::*;
use nlrt_poly::glam::DVec3;

/// Names of the built-in scenes: displacement mapping (mountain, cylinder, fur) and shell
/// mapping (scales, cornell, fig9). `torus` is the watertightness scene of the paper's Fig. 8,
/// `fig9` its Fig. 9 (degenerate base meshes and prisms).
pub const SCENE_NAMES: [&str; 9] = [
    "mountain", "cylinder", "fur", "torus", "feathers", "scales", "cornell", "highpoly", "fig9",
];

/// Scenes whose rays `nlrt watertight` can decide (displacement scenes: closed meshes, or the
/// mountain's convex shell) and the report measures.
pub const WATERTIGHT_SCENES: [&str; 6] = [
    "torus",
    "fur",
    "mountain",
    "mountain-grazing",
    "fig9-displaced",
    "seam-cube",
];

/// The ghost-hit tori ([`ghost_torus`]): judged by `nlrt watertight`, not by the report
/// (their figures are in `docs/watertightness.md`).
pub const GHOST_SCENES: [&str; 3] = ["torus-spikes", "torus-tilted", "torus-twisted"];

/// The uv-seam scenes ([`seam_cube`], [`seam_sphere`]): base meshes whose atlas is cut, so
/// the two sides of each seam sample different texels.
pub const SEAM_SCENES: [&str; 2] = ["seam-cube", "seam-sphere"];

/// Built-in scene variants made for one measurement, not part of the default report's
/// renders: `mountain-grazing` (the mountain seen at grazing angles), `fur-cones` (the fur's
/// torus under broad cones, [`fur_cones`]), `fig9-displaced` (Fig.
/// 9's columns with a height map), the ghost-hit tori ([`ghost_torus`]) and the seam scenes
/// ([`SEAM_SCENES`]), the coarse tori ([`COARSE_TORI`]), `mountain-midlevel` and
/// `torus-midlevel` (the mountain and the torus with midlevel 0.5: the maps push in and out),
/// and `dem-crop` ([`dem_crop`]: a map neither square nor a power of two), for
/// `nlrt watertight`, and usable everywhere a scene is.
pub const VARIANT_NAMES: [&str; 20] = [
    "dem-crop",
    "mountain-midlevel",
    "torus-midlevel",
    COARSE_TORI[0].0,
    COARSE_TORI[1].0,
    COARSE_TORI[2].0,
    COARSE_TORI[3].0,
    COARSE_TORI[4].0,
    COARSE_TORI[5].0,
    COARSE_TORI[6].0,
    COARSE_TORI[7].0,
    COARSE_TORI[8].0,
    "mountain-grazing",
    "fur-cones",
    "fig9-displaced",
    "torus-spikes",
    "torus-tilted",
    "torus-twisted",
    "seam-cube",
    "seam-sphere",
];

/// Whether `name` is a built-in scene or variant.
#[must_use]
pub fn is_builtin(name: &str) -> bool {
    SCENE_NAMES.contains(&name) || VARIANT_NAMES.contains(&name)
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
    let map = |paper, small| size.pick(paper, small);
    match name {
        "mountain" => Some(mountain(map(4096, 1024))),
        "cylinder" => Some(cylinder(map(4096, 1024))),
        "fur" => Some(fur(map(256, 64))),
        "fur-cones" => Some(fur_cones(map(256, 64))),
        "torus" => Some(torus_scene(map(1024, 256))),
        "mountain-grazing" => {
            // The watertightness view of the mountain: just above the shell's top, over the
            // map's edge, looking across it about 4 degrees down.
            let mut m = mountain(map(4096, 1024));
            m.name = "mountain-grazing";
            m.camera.eye = DVec3::new(0.0, 0.4, 0.95);
            m.camera.target = DVec3::new(0.0, 0.25, -1.0);
            Some(m)
        }
        "mountain-midlevel" | "torus-midlevel" => {
            let mut scene = if name == "mountain-midlevel" {
                mountain(map(4096, 1024))
            } else {
                torus_scene(map(1024, 256))
            };
            scene.name = if name == "mountain-midlevel" {
                "mountain-midlevel"
            } else {
                "torus-midlevel"
            };
            scene.midlevel = 0.5;
            Some(scene)
        }
        "dem-crop" => Some(dem_crop(if size == Size::Small { 150 } else { 601 })),
        "scales" => Some(scales()),
        "fig9" => Some(fig9()),
        "fig9-displaced" => Some(fig9_displaced(map(1024, 256))),
        "torus-spikes" | "torus-tilted" | "torus-twisted" => ghost_torus(name, map(256, 64)),
        _ if name.starts_with("torus-coarse") => COARSE_TORI
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(n, shape)| coarse_torus(n, shape, map(256, 64))),
        "cornell" => Some(cornell(size.detail(15, 6))),
        "seam-cube" => Some(seam_cube(map(1024, 256))),
        "seam-sphere" => Some(seam_sphere(map(1024, 256))),
        "feathers" => Some(feathers()),
        "highpoly" => Some(highpoly(size.detail(270, 32))),
        _ => None,
    }
}
