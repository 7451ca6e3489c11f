//! `ks-fit render SHAPE.obj --out FILE.png`, and the pictures other commands write
//! (`scene.png`): options, the renderer's start-up, and what is said when there is no GPU.

use crate::guard::Guard;
use kshell::render::{
    bounds, parse_size, read_shape, Ground, Image, RenderOptions, Renderer, View, BACKGROUND,
};
use std::path::{Path, PathBuf};

/// The flags of `ks-fit render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Wavefront OBJ shape(s).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Shapes per row when there are several (default: up to 5).
    #[arg(long)]
    pub columns: Option<usize>,
    /// PNG file to write.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub image: ImageArgs,
}

/// Picture options shared by every command that draws.
#[derive(clap::Args, Clone, Debug)]
pub struct ImageArgs {
    /// Picture size in pixels, WxH.
    #[arg(long = "image", value_parser = parse_size, default_value = "1600x1200")]
    pub size: (u32, u32),
    /// Camera: `auto` (front for hanging shapes, from above for flat ones), `front` or `above`.
    #[arg(long, value_enum, default_value = "auto")]
    pub view: ViewArg,
    /// Ground plane with the cloth's shadow: `auto` (under hanging shapes), `on` or `off`.
    #[arg(long, value_enum, default_value = "auto")]
    pub ground: GroundArg,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum ViewArg {
    Auto,
    Front,
    Above,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum GroundArg {
    Auto,
    On,
    Off,
}

impl ImageArgs {
    pub fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.size.0,
            height: self.size.1,
            view: match self.view {
                ViewArg::Auto => View::Auto,
                ViewArg::Front => View::Front,
                ViewArg::Above => View::Above,
            },
            ground: match self.ground {
                GroundArg::Auto => Ground::Auto,
                GroundArg::On => Ground::On,
                GroundArg::Off => Ground::Off,
            },
            line_spacing: None,
            frame: None,
        }
    }
}

/// Mesa's software Vulkan driver warns on stderr when XDG_RUNTIME_DIR is unset (a harmless
/// message that reads like an error); give it a private folder first. Called before any thread
/// starts.
pub fn quiet_driver_warnings() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("ks-fit-runtime-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_ok() {
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
        }
        // SAFETY-free in edition 2021; no other thread exists yet
        std::env::set_var("XDG_RUNTIME_DIR", &dir);
    }
}

/// Removes the folder [`quiet_driver_warnings`] made, if any.
pub fn cleanup_driver_folder() {
    let dir = std::env::temp_dir().join(format!("ks-fit-runtime-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(dir);
}

/// `ks-fit render`: one shape, or several side by side (`columns` per row) framed by one box so
/// that they share a scale.
pub fn cmd_render(
    files: &[PathBuf],
    out: &Path,
    columns: Option<usize>,
    args: &ImageArgs,
    force: bool,
) -> Result<(), String> {
    let mut guard = Guard::new(force);
    for f in files {
        guard.input(f);
    }
    guard.file("--out", out)?;
    if columns == Some(0) {
        return Err("--columns must be at least 1".into());
    }
    let meshes = files
        .iter()
        .map(|f| read_shape(f).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let renderer = Renderer::new().map_err(|e| e.to_string())?;
    let t0 = std::time::Instant::now();
    let mut opts = args.options();
    if meshes.len() > 1 {
        let all: Vec<kshell::Vec3> = meshes.iter().flat_map(|m| m.positions.clone()).collect();
        opts.frame = Some(bounds(&all));
    }
    let images = meshes
        .iter()
        .map(|m| renderer.render_mesh(m, &opts).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let columns = columns.unwrap_or(images.len().min(5));
    let image = Image::grid(&images, columns, BACKGROUND);
    let png = image.png().map_err(|e| e.to_string())?;
    kshell::io::write_atomic(out, png).map_err(|e| format!("writing {}: {e}", out.display()))?;
    eprintln!(
        "ks-fit: render: {} shape(s), {} triangles, {}x{} on {} in {:.2} s; wrote {}",
        meshes.len(),
        meshes.iter().map(|m| m.triangles.len()).sum::<usize>(),
        image.width,
        image.height,
        renderer.adapter_name(),
        t0.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}
