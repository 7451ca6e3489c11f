//! `ks-fit render SHAPE.obj --out FILE.png`, and the pictures other commands write
//! (`scene.png`): options, the renderer's start-up, and what is said when there is no GPU.

use crate::guard::Guard;
use kshell::render::{parse_size, read_shape, Ground, RenderOptions, Renderer, View};
use std::path::Path;

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

/// `ks-fit render`.
pub fn cmd_render(file: &Path, out: &Path, args: &ImageArgs, force: bool) -> Result<(), String> {
    let mut guard = Guard::new(force);
    guard.input(file);
    guard.file("--out", out)?;
    let mesh = read_shape(file).map_err(|e| e.to_string())?;
    let renderer = Renderer::new().map_err(|e| e.to_string())?;
    let t0 = std::time::Instant::now();
    let image = renderer
        .render_mesh(&mesh, &args.options())
        .map_err(|e| e.to_string())?;
    let png = image.png().map_err(|e| e.to_string())?;
    kshell::io::write_atomic(out, png).map_err(|e| format!("writing {}: {e}", out.display()))?;
    eprintln!(
        "ks-fit: render: {} triangles on {} in {:.2} s; wrote {}",
        mesh.triangles.len(),
        renderer.adapter_name(),
        t0.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}
