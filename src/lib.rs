//! kshell: simulation-ready cloth materials from standard fabric lab tests.
//!
//! The crate follows the pipeline of Clyde, Teran & Tamstorf, "Modeling and Data-Driven Parameter
//! Estimation for Woven Fabrics" (SCA 2017), one module per stage:
//!
//! | module | owns |
//! |---|---|
//! | [`mesh`] | quad control meshes: OBJ input/output, grids, topology checks, uniform Catmull–Clark refinement |
//! | [`subdiv`] | the exact Catmull–Clark limit basis: per-point stencils for x, x_u, x_v, x_uu, x_uv, x_vv |
//! | [`quadrature`] | Gauss–Legendre rules on faces and through the thickness |
//! | [`dataset`] | the fabric dataset: `fabric.toml` and its CSV curves, read, checked, written |
//! | [`shape`] | captured static shapes (OBJ) as fit targets: closest-point distances and the FFT descriptor |
//! | [`synth`] | synthetic datasets from a material through the virtual lab |
//! | [`io`] | safe output (temporary file and rename) and plain number printing |
//! | [`render`] | pictures: the limit surface tessellated by a GPU kernel (`shaders/`), shaded with its yarn lines, PNG |
//! | [`limits`] | resource limits checked before allocating (faces of a mesh) |
//!
//! Later stages (shell kinematics, material, assembly, solve, scene, fit, report) hand data on as
//! plain structs of arrays; see `docs/design.md` in the repository for the map.

pub mod assembly;
pub mod atlas;
pub mod converge;
pub mod dataset;
pub mod fit;
pub mod io;
pub mod limits;
pub mod material;
pub mod mesh;
pub mod model;
pub mod quadrature;
pub mod recommend;
pub mod render;
pub mod scene;
pub mod shape;
pub mod shell;
pub mod solve;
pub mod subdiv;
pub mod synth;
pub mod tri;

/// A point or vector in 3-space, SI units inside the engine.
pub type Vec3 = [f64; 3];
