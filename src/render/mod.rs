//! Pictures of cloth: a dense tessellation of the limit surface evaluated on the GPU, shaded with
//! a warp/weft line texture so that stretch and shear show as in Clyde et al. 2017 Figure 5, with
//! a ground shadow for hanging shapes; written as PNG.
//!
//! Owns: the stencil table of a tessellation and its CPU oracle ([`Tessellation`]), the camera
//! ([`Camera`]), triangle meshes read from written shapes ([`read_shape`]), images and PNG
//! ([`Image`]), and, with the `render` feature, the wgpu renderer ([`Renderer`]) whose kernels are
//! the WGSL files in `shaders/`: `limit_eval.wgsl` applies the limit stencils to the control points
//! (one invocation per sample, as OpenSubdiv's GPU stencil evaluators do) and `cloth.wgsl` draws
//! the ground, the shadow and the cloth.
//!
//! Nothing else in kshell needs a GPU: without an adapter (or without the feature) the renderer
//! says so and callers go on without the picture.

mod camera;
mod image;
mod shape;
mod tessellate;

#[cfg(feature = "render")]
mod gpu;

pub use camera::{Camera, View};
pub use image::Image;
pub use shape::{parse_shape, read_shape, RenderMesh};
pub use tessellate::{bounds, Sample, Tessellation};

#[cfg(feature = "render")]
pub use gpu::Renderer;

/// What can go wrong making a picture.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("no GPU adapter found ({0}); install a Vulkan driver (on Debian or Ubuntu: apt-get install mesa-vulkan-drivers, Mesa's software driver lavapipe) or run on a machine with a GPU")]
    NoAdapter(String),
    #[error("this ks-fit was built without the `render` feature: no pictures")]
    NotBuiltIn,
    #[error("the GPU device failed: {0}")]
    Device(String),
    #[error("image size {0}x{1} is out of range (1 to {2} pixels each way)")]
    Size(u32, u32, u32),
    #[error("nothing to draw: the shape has no triangles")]
    Empty,
    #[error("PNG encoding failed: {0}")]
    Png(String),
}

/// Where the ground and its shadow are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ground {
    /// Under shapes that hang (taller than a third of their width), not under flat ones.
    Auto,
    On,
    Off,
}

/// How a picture is made.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub view: View,
    pub ground: Ground,
    /// Spacing of the warp and weft lines in metres of fabric (None: about 16 across the piece,
    /// rounded to 1, 2 or 5 × a power of ten).
    pub line_spacing: Option<f64>,
    /// The box the camera frames and the ground is placed under (None: the shape's own), so
    /// that several shapes drawn alike share one scale.
    pub frame: Option<(crate::Vec3, crate::Vec3)>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 1600,
            height: 1200,
            view: View::Auto,
            ground: Ground::Auto,
            line_spacing: None,
            frame: None,
        }
    }
}

/// Background colour of every picture (RGBA8); nothing drawn has it.
pub const BACKGROUND: [u8; 4] = [247, 247, 247, 255];

/// Largest image side accepted (the common GPU texture limit).
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// Parses "WxH" (e.g. "1600x1200").
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("image size {s:?}: expected WxH, e.g. 1600x1200"))?;
    let side = |t: &str| -> Result<u32, String> {
        match t.trim().parse::<u32>() {
            Ok(v) if (1..=MAX_IMAGE_SIDE).contains(&v) => Ok(v),
            _ => Err(format!(
                "image size {s:?}: each side must be a whole number from 1 to {MAX_IMAGE_SIDE}"
            )),
        }
    };
    Ok((side(w)?, side(h)?))
}

/// A line spacing of about a sixteenth of `extent`, rounded down to 1, 2 or 5 × 10ⁿ.
pub fn auto_line_spacing(extent: f64) -> f64 {
    let raw = (extent / 16.0).max(1e-9);
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    let nice = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    nice * p
}

/// A renderer that is not there: every call says the feature is off.
#[cfg(not(feature = "render"))]
pub struct Renderer;

#[cfg(not(feature = "render"))]
impl Renderer {
    pub fn new() -> Result<Self, RenderError> {
        Err(RenderError::NotBuiltIn)
    }
    pub fn adapter_name(&self) -> String {
        String::new()
    }
    pub fn render_mesh(&self, _: &RenderMesh, _: &RenderOptions) -> Result<Image, RenderError> {
        Err(RenderError::NotBuiltIn)
    }
    pub fn render_limit(
        &self,
        _: &Tessellation,
        _: &[crate::Vec3],
        _: &RenderOptions,
    ) -> Result<Image, RenderError> {
        Err(RenderError::NotBuiltIn)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_refuse() {
        assert_eq!(parse_size("1600x1200"), Ok((1600, 1200)));
        assert_eq!(parse_size("64X48"), Ok((64, 48)));
        assert!(parse_size("1600").is_err());
        assert!(parse_size("0x10").is_err());
        assert!(parse_size("10x99999").is_err());
    }

    #[test]
    fn line_spacing_is_a_round_number() {
        assert!((auto_line_spacing(1.0) - 0.05).abs() < 1e-12);
        assert!((auto_line_spacing(0.1) - 0.005).abs() < 1e-12);
        assert!((auto_line_spacing(0.05) - 0.002).abs() < 1e-12);
    }
}
