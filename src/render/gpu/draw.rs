//! One frame drawn and read back: the frame uniform (camera, light, texture lines, ground),
//! the multisampled targets, the ground, shadow and cloth passes, and the copy of the resolved
//! image into host memory.

use super::{Frame, Renderer, CLOTH_RGB, COLOR, DEPTH, LIGHT, SAMPLES};
use crate::render::camera::{hangs, Camera};
use crate::render::{auto_line_spacing, Ground, Image, RenderError, RenderOptions, BACKGROUND};
use crate::Vec3;

/// What one draw needs: vertices (GPU buffer of [`Vertex`]), texture coordinates, triangles.
pub(super) struct Draw<'a> {
    pub vertices: &'a wgpu::Buffer,
    pub uv: &'a wgpu::Buffer,
    pub index: &'a wgpu::Buffer,
    pub index_count: u32,
    pub lo: Vec3,
    pub hi: Vec3,
    pub textured: bool,
    pub uv_extent: f64,
}

/// The multisampled colour and depth targets and the resolved colour target of one frame.
struct Targets {
    msaa: wgpu::TextureView,
    depth: wgpu::TextureView,
    resolved_view: wgpu::TextureView,
    resolved: wgpu::Texture,
}

impl Renderer {
    pub(super) fn draw(
        &self,
        encoder: wgpu::CommandEncoder,
        d: &Draw,
        opts: &RenderOptions,
    ) -> Result<Image, RenderError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let image = self.draw_unscoped(encoder, d, opts);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(e.to_string()));
        }
        image
    }

    fn draw_unscoped(
        &self,
        mut encoder: wgpu::CommandEncoder,
        d: &Draw,
        opts: &RenderOptions,
    ) -> Result<Image, RenderError> {
        let (w, h) = (opts.width, opts.height);
        let (frame, ground) = frame_uniform(d, opts);
        let bind = self.frame_bind_group(&frame);
        let targets = self.targets(w, h);
        self.record_passes(&mut encoder, d, &bind, &targets, ground);
        self.copy_out(encoder, &targets.resolved, w, h)
    }

    /// The frame uniform in a buffer, bound for the render pipelines.
    fn frame_bind_group(&self, frame: &Frame) -> wgpu::BindGroup {
        let frame_buf = self.buffer(
            "frame",
            bytemuck::bytes_of(frame),
            wgpu::BufferUsages::UNIFORM,
        );
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &self.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buf.as_entire_binding(),
            }],
        })
    }

    /// The frame's render targets, `w` × `h`.
    fn targets(&self, w: u32, h: u32) -> Targets {
        let target = |samples: u32, format: wgpu::TextureFormat, usage: wgpu::TextureUsages| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let msaa = target(SAMPLES, COLOR, attach);
        let depth = target(SAMPLES, DEPTH, attach);
        let resolved = target(1, COLOR, attach | wgpu::TextureUsages::COPY_SRC);
        let (msaa_view, depth_view, resolved_view) = (
            msaa.create_view(&Default::default()),
            depth.create_view(&Default::default()),
            resolved.create_view(&Default::default()),
        );
        Targets {
            msaa: msaa_view,
            depth: depth_view,
            resolved_view,
            resolved,
        }
    }

    /// Records the frame's render pass: the ground and the cloth's shadow on it (where
    /// `ground`), then the cloth.
    fn record_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        d: &Draw,
        bind: &wgpu::BindGroup,
        targets: &Targets,
        ground: bool,
    ) {
        let bg = BACKGROUND.map(|c| c as f64 / 255.0);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("cloth"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.msaa,
                    depth_slice: None,
                    resolve_target: Some(&targets.resolved_view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: bg[0],
                            g: bg[1],
                            b: bg[2],
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(0, bind, &[]);
            if ground {
                pass.set_pipeline(&self.ground);
                pass.draw(0..6, 0..1);
                pass.set_pipeline(&self.shadow);
                pass.set_vertex_buffer(0, d.vertices.slice(..));
                pass.set_index_buffer(d.index.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..d.index_count, 0, 0..1);
            }
            pass.set_pipeline(&self.cloth);
            pass.set_vertex_buffer(0, d.vertices.slice(..));
            pass.set_vertex_buffer(1, d.uv.slice(..));
            pass.set_index_buffer(d.index.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..d.index_count, 0, 0..1);
        }
    }

    /// Submits `encoder` with a copy of the resolved image and reads it back as RGBA rows.
    fn copy_out(
        &self,
        mut encoder: wgpu::CommandEncoder,
        resolved: &wgpu::Texture,
        w: u32,
        h: u32,
    ) -> Result<Image, RenderError> {
        let row = (4 * w).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: row as u64 * h as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: resolved,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        let bytes = self.read_back(encoder, &readback, readback.size(), Some(readback.clone()))?;
        let mut rgba = Vec::with_capacity(4 * (w * h) as usize);
        for y in 0..h as usize {
            let start = y * row as usize;
            rgba.extend_from_slice(&bytes[start..start + 4 * w as usize]);
        }
        Ok(Image {
            width: w,
            height: h,
            rgba,
        })
    }
}

/// The frame uniform of drawing `d` under `opts`, and whether the ground is drawn.
fn frame_uniform(d: &Draw, opts: &RenderOptions) -> (Frame, bool) {
    let (w, h) = (opts.width, opts.height);
    let (lo, hi) = opts.frame.unwrap_or((d.lo, d.hi));
    let cam = Camera::frame(lo, hi, opts.view, w, h);
    let ground = match opts.ground {
        Ground::On => true,
        Ground::Off => false,
        Ground::Auto => hangs(lo, hi),
    };
    let size = (0..3).map(|c| hi[c] - lo[c]).fold(0.0, f64::max);
    let spacing = opts
        .line_spacing
        .unwrap_or_else(|| auto_line_spacing(d.uv_extent.max(1e-9)));
    let light = unit(LIGHT);
    let (cx, cy) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
    let reach = 5.0 * size;
    let frame = Frame {
        view_proj: cam.columns_f32(),
        eye: [cam.eye[0] as f32, cam.eye[1] as f32, cam.eye[2] as f32, 1.0],
        light: [light[0] as f32, light[1] as f32, light[2] as f32, 0.0],
        cloth: [
            CLOTH_RGB[0],
            CLOTH_RGB[1],
            CLOTH_RGB[2],
            if d.textured { 1.0 } else { 0.0 },
        ],
        lines: [
            spacing as f32,
            1.5 * (w.min(h) as f32 / 1200.0).max(1.0),
            0.0,
            0.0,
        ],
        ground: [(lo[2] - 0.03 * size) as f32, 0.0, 0.0, 0.0],
        ground_rect: [
            (cx - reach) as f32,
            (cy - reach) as f32,
            (cx + reach) as f32,
            (cy + reach) as f32,
        ],
    };
    (frame, ground)
}

fn unit(a: Vec3) -> Vec3 {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}
