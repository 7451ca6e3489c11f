//! A showcase scene's final state on either discretisation, and what `ks-fit scene` makes of
//! it: the counts and stability it reports, the surface it writes (OBJ, PLY) and the picture
//! it draws (the shell's limit surface tessellated on the GPU; a triangle model's sheet as its
//! own quads).

use kshell::scene::export::{lattice_surface, sample, SurfaceMesh};
use kshell::scene::sheet::SolveCounts;
use kshell::scene::{Deformed, SceneError};
use kshell::tri::file::TriSource;
use kshell::tri::{TriKind, TriModel};
use kshell::Vec3;
use std::time::Instant;

/// The first line of every `scene.toml` that `ks-fit scene` writes (the scene's name follows).
pub const SCENE_TOML_MARK: &str = "# written by ks-fit scene ";

/// What marks a folder as an earlier `ks-fit scene --out`: a scene.toml that a scene wrote.
pub const SCENE: crate::guard::Marker = crate::guard::Marker {
    file: "scene.toml",
    ours: |text| text.starts_with(SCENE_TOML_MARK),
};

/// The material a scene runs: the shell's law, or a triangle model's parameters (from the
/// file's [model] table, or converted from the shell law at each mesh's cell size).
pub enum SceneMaterial {
    Shell(kshell::material::FabricMaterial),
    Tri(TriKind, TriSource),
}

impl SceneMaterial {
    /// A triangle model's parameters on cells of `cell` metres (springs scale with it).
    pub fn tri(&self, cell: f64) -> Result<Option<kshell::tri::TriMaterial>, SceneError> {
        match self {
            SceneMaterial::Shell(_) => Ok(None),
            SceneMaterial::Tri(kind, source) => source
                .material(*kind, cell)
                .map(Some)
                .map_err(SceneError::Input),
        }
    }
}

/// A scene's final state.
/// (Boxed: the deformed models are large, and a shape is moved around whole.)
pub enum Shape {
    Shell(Box<Deformed>),
    Tri(Box<Deformed<TriModel>>),
}

impl Shape {
    pub fn counts(&self) -> &SolveCounts {
        match self {
            Shape::Shell(d) => &d.counts,
            Shape::Tri(d) => &d.counts,
        }
    }

    pub fn stable(&self) -> bool {
        match self {
            Shape::Shell(d) => d.stable,
            Shape::Tri(d) => d.stable,
        }
    }

    pub fn x(&self) -> &[Vec3] {
        match self {
            Shape::Shell(d) => &d.x,
            Shape::Tri(d) => &d.x,
        }
    }

    /// The surface written as OBJ and PLY: the shell's limit surface 4 × 4 per face, a
    /// triangle model's nodes.
    pub fn surface(&self) -> Result<SurfaceMesh, String> {
        match self {
            Shape::Shell(d) => sample(&d.sheet, &d.x, 4).map_err(|e| e.to_string()),
            Shape::Tri(d) => Ok(lattice_surface(&d.sheet, &d.x)),
        }
    }

    /// The picture, drawn by `renderer`, and a line saying what was drawn.
    pub fn picture(
        &self,
        renderer: &kshell::render::Renderer,
        mesh: usize,
        opts: &kshell::render::RenderOptions,
    ) -> Result<(kshell::render::Image, String), String> {
        let t0 = Instant::now();
        match self {
            Shape::Shell(d) => {
                let k = samples_per_face(mesh);
                let tess = kshell::render::Tessellation::new(
                    d.sheet.model.basis.surface(),
                    d.sheet.rest(),
                    k,
                )
                .map_err(|e| e.to_string())?;
                let image = renderer
                    .render_limit(&tess, &d.x, opts)
                    .map_err(|e| e.to_string())?;
                let what = format!(
                    "{} limit samples ({k}x{k} per face) on {} in {:.2} s",
                    tess.num_points(),
                    renderer.adapter_name(),
                    t0.elapsed().as_secs_f64()
                );
                Ok((image, what))
            }
            Shape::Tri(d) => {
                let surface = lattice_surface(&d.sheet, &d.x);
                let image = renderer
                    .render_mesh(&(&surface).into(), opts)
                    .map_err(|e| e.to_string())?;
                let what = format!(
                    "the triangle model's {} nodes on {} in {:.2} s",
                    surface.positions.len(),
                    renderer.adapter_name(),
                    t0.elapsed().as_secs_f64()
                );
                Ok((image, what))
            }
        }
    }
}

/// Samples per cage face and side of the picture's tessellation: about 128 across the sheet.
fn samples_per_face(mesh: usize) -> usize {
    (128 / mesh.max(1)).clamp(2, 16)
}
