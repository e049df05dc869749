//! What is traced: scenes and what they are made of. Depends on no other group of this crate.

mod map_file;
pub mod material;
pub mod motion;
pub mod scene_file;
pub mod scenes;
