//! How rays meet a scene: the tracer interface, the methods, several objects as one, the
//! path tracer and its images. Depends on [`crate::scene`] only.

#[cfg(feature = "embree")]
pub mod embree_grid;
#[cfg(feature = "embree")]
pub mod embree_reference;
#[cfg(feature = "embree")]
pub mod embree_user;
pub mod geometry_image;
pub mod grid_mesh;
pub mod image;
pub mod integrator;
pub mod method;
pub mod methods;
pub mod objects;
pub mod ray_stream;
pub mod tessellate;
pub mod tracer;
