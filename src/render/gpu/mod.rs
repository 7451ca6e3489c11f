//! The wgpu renderer: a headless device, the limit-evaluation compute pipeline
//! (`shaders/limit_eval.wgsl`) and the ground, shadow and cloth pipelines (`shaders/cloth.wgsl`),
//! drawn 4× multisampled into an RGBA8 target that is read back.

use super::camera::{hangs, Camera};
use super::tessellate::{bounds, Tessellation};
use super::{auto_line_spacing, Ground, Image, RenderError, RenderMesh, RenderOptions, BACKGROUND};
use crate::Vec3;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

const LIMIT_EVAL: &str = include_str!("../../shaders/limit_eval.wgsl");
const CLOTH: &str = include_str!("../../shaders/cloth.wgsl");
const SAMPLES: u32 = 4;
const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const WORKGROUP: u32 = 64;
/// Cloth colour, linear RGB as written.
const CLOTH_RGB: [f32; 3] = [0.86, 0.80, 0.70];
/// Towards the light: from above, in front and to the left of the front view.
const LIGHT: Vec3 = [-0.3, -0.5, 1.0];

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Frame {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light: [f32; 4],
    cloth: [f32; 4],
    lines: [f32; 4],
    ground: [f32; 4],
    ground_rect: [f32; 4],
}

/// A vertex as the compute kernel writes it and the cloth pipeline reads it.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Vertex {
    position: [f32; 4],
    normal: [f32; 4],
}

/// A GPU device with the kernels compiled.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: String,
    eval_layout: wgpu::BindGroupLayout,
    eval: wgpu::ComputePipeline,
    frame_layout: wgpu::BindGroupLayout,
    ground: wgpu::RenderPipeline,
    shadow: wgpu::RenderPipeline,
    cloth: wgpu::RenderPipeline,
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

const VERTEX_ATTRS: [wgpu::VertexAttribute; 2] =
    wgpu::vertex_attr_array![0 => Float32x4, 1 => Float32x4];
const UV_ATTRS: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![2 => Float32x2];

fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRS,
    }
}

fn uv_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: 8,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &UV_ATTRS,
    }
}

/// What one draw needs: vertices (GPU buffer of [`Vertex`]), texture coordinates, triangles.
struct Draw<'a> {
    vertices: &'a wgpu::Buffer,
    uv: &'a wgpu::Buffer,
    index: &'a wgpu::Buffer,
    index_count: u32,
    lo: Vec3,
    hi: Vec3,
    textured: bool,
    uv_extent: f64,
}

impl Renderer {
    /// Opens the first adapter wgpu finds (a software one if that is all there is).
    pub fn new() -> Result<Self, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let name = format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("kshell"),
            required_features: wgpu::Features::empty(),
            required_limits: adapter.limits(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        // errors are caught by the scopes below; one that escapes them is reported, not a panic
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            eprintln!("GPU error: {e}");
        }));
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let eval_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("limit_eval.wgsl"),
            source: wgpu::ShaderSource::Wgsl(LIMIT_EVAL.into()),
        });
        let cloth_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("cloth.wgsl"),
            source: wgpu::ShaderSource::Wgsl(CLOTH.into()),
        });
        let eval_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("limit_eval"),
            entries: &[
                storage(0, true),
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, false),
                uniform(5, wgpu::ShaderStages::COMPUTE),
            ],
        });
        let eval_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("limit_eval"),
            bind_group_layouts: &[Some(&eval_layout)],
            immediate_size: 0,
        });
        let eval = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("limit_eval"),
            layout: Some(&eval_pipeline_layout),
            module: &eval_module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[uniform(
                0,
                wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
            )],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("frame"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });
        let pipeline = |name: &str, buffers: &[Option<wgpu::VertexBufferLayout>], depth: bool| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(name),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &cloth_module,
                    entry_point: Some(&format!("vs_{name}")),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH,
                    depth_write_enabled: Some(depth),
                    depth_compare: Some(if depth {
                        wgpu::CompareFunction::Less
                    } else {
                        wgpu::CompareFunction::Always
                    }),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: SAMPLES,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &cloth_module,
                    entry_point: Some(&format!("fs_{name}")),
                    compilation_options: Default::default(),
                    targets: &[Some(COLOR.into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let ground = pipeline("ground", &[], false);
        let shadow_vertex = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<Vertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &VERTEX_ATTRS[..1],
        };
        let shadow = pipeline("shadow", &[Some(shadow_vertex)], false);
        let cloth = pipeline("cloth", &[Some(vertex_layout()), Some(uv_layout())], true);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(e.to_string()));
        }
        Ok(Self {
            device,
            queue,
            adapter: name,
            eval_layout,
            eval,
            frame_layout,
            ground,
            shadow,
            cloth,
        })
    }

    /// The adapter in use, e.g. "llvmpipe (LLVM 15, 256 bits) (Vulkan, Cpu)".
    pub fn adapter_name(&self) -> String {
        self.adapter.clone()
    }

    fn buffer(&self, label: &str, data: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: data,
                usage,
            })
    }

    /// Records the limit evaluation of `tess` at control points `x` into a new vertex buffer.
    fn record_eval(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        tess: &Tessellation,
        x: &[Vec3],
    ) -> Result<wgpu::Buffer, RenderError> {
        let n = tess.num_points() as u32;
        let groups = n.div_ceil(WORKGROUP);
        let max = self.device.limits().max_compute_workgroups_per_dimension;
        if groups > max || n == 0 || x.len() < tess.num_controls() {
            return Err(RenderError::Device(format!(
                "{n} samples on {} control points ({} needed; at most {} samples per dispatch)",
                x.len(),
                tess.num_controls(),
                max as u64 * WORKGROUP as u64
            )));
        }
        let control: Vec<[f32; 4]> = x
            .iter()
            .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 1.0])
            .collect();
        let st = wgpu::BufferUsages::STORAGE;
        let control = self.buffer("control", bytemuck::cast_slice(&control), st);
        let offsets = self.buffer("offsets", bytemuck::cast_slice(&tess.offsets), st);
        let indices = self.buffer("indices", bytemuck::cast_slice(&tess.indices), st);
        let weights = self.buffer("weights", bytemuck::cast_slice(&tess.weights), st);
        let params = self.buffer(
            "params",
            bytemuck::cast_slice(&[n, 0, 0, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let vertices = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vertices"),
            size: n as u64 * std::mem::size_of::<Vertex>() as u64,
            usage: st | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("limit_eval"),
            layout: &self.eval_layout,
            entries: &[
                (0, &control),
                (1, &offsets),
                (2, &indices),
                (3, &weights),
                (4, &vertices),
                (5, &params),
            ]
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }),
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("limit_eval"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.eval);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(groups, 1, 1);
        drop(pass);
        Ok(vertices)
    }

    /// Limit positions and unit normals of every sample of `tess` at control points `x`,
    /// evaluated by the compute kernel and read back: [x, y, z, 1, nx, ny, nz, 0] per sample.
    pub fn evaluate(&self, tess: &Tessellation, x: &[Vec3]) -> Result<Vec<[f32; 8]>, RenderError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let vertices = self.record_eval(&mut encoder, tess, x)?;
        let bytes = self.read_back(encoder, &vertices, vertices.size(), None);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(e.to_string()));
        }
        let bytes = bytes?;
        Ok(bytemuck::cast_slice::<u8, [f32; 8]>(&bytes).to_vec())
    }

    /// Renders the limit surface of `tess` at control points `x` (tessellated on the GPU).
    pub fn render_limit(
        &self,
        tess: &Tessellation,
        x: &[Vec3],
        opts: &RenderOptions,
    ) -> Result<Image, RenderError> {
        check_size(opts)?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let vertices = self.record_eval(&mut encoder, tess, x)?;
        let (lo, hi) = bounds(x);
        let uv = self.buffer(
            "uv",
            bytemuck::cast_slice(&tess.uv),
            wgpu::BufferUsages::VERTEX,
        );
        let index = self.buffer(
            "triangles",
            bytemuck::cast_slice(&tess.triangles),
            wgpu::BufferUsages::INDEX,
        );
        let (ulo, uhi) = uv_bounds(tess.uv.iter().map(|t| [t[0] as f64, t[1] as f64]));
        let draw = Draw {
            vertices: &vertices,
            uv: &uv,
            index: &index,
            index_count: 3 * tess.triangles.len() as u32,
            lo,
            hi,
            textured: true,
            uv_extent: (uhi[0] - ulo[0]).max(uhi[1] - ulo[1]),
        };
        self.draw(encoder, &draw, opts)
    }

    /// Renders a triangle mesh (e.g. a shape read from OBJ).
    pub fn render_mesh(
        &self,
        mesh: &RenderMesh,
        opts: &RenderOptions,
    ) -> Result<Image, RenderError> {
        check_size(opts)?;
        if mesh.triangles.is_empty() {
            return Err(RenderError::Empty);
        }
        let verts: Vec<Vertex> = mesh
            .positions
            .iter()
            .zip(&mesh.normals)
            .map(|(p, n)| Vertex {
                position: [p[0] as f32, p[1] as f32, p[2] as f32, 1.0],
                normal: [n[0] as f32, n[1] as f32, n[2] as f32, 0.0],
            })
            .collect();
        let uvs: Vec<[f32; 2]> = match &mesh.uv {
            Some(uv) => uv.iter().map(|t| [t[0] as f32, t[1] as f32]).collect(),
            None => vec![[0.0; 2]; verts.len()],
        };
        let (ulo, uhi) = uv_bounds(mesh.uv.iter().flatten().copied());
        let vertices = self.buffer(
            "vertices",
            bytemuck::cast_slice(&verts),
            wgpu::BufferUsages::VERTEX,
        );
        let uv = self.buffer("uv", bytemuck::cast_slice(&uvs), wgpu::BufferUsages::VERTEX);
        let index = self.buffer(
            "triangles",
            bytemuck::cast_slice(&mesh.triangles),
            wgpu::BufferUsages::INDEX,
        );
        let (lo, hi) = bounds(&mesh.positions);
        let draw = Draw {
            vertices: &vertices,
            uv: &uv,
            index: &index,
            index_count: 3 * mesh.triangles.len() as u32,
            lo,
            hi,
            textured: mesh.uv.is_some(),
            uv_extent: (uhi[0] - ulo[0]).max(uhi[1] - ulo[1]),
        };
        let encoder = self.device.create_command_encoder(&Default::default());
        self.draw(encoder, &draw, opts)
    }

    fn draw(
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
        let frame_buf = self.buffer(
            "frame",
            bytemuck::bytes_of(&frame),
            wgpu::BufferUsages::UNIFORM,
        );
        let bind = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &self.frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame_buf.as_entire_binding(),
            }],
        });
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
        let bg = BACKGROUND.map(|c| c as f64 / 255.0);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("cloth"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &msaa_view,
                    depth_slice: None,
                    resolve_target: Some(&resolved_view),
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
                    view: &depth_view,
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
            pass.set_bind_group(0, &bind, &[]);
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
                texture: &resolved,
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

    /// Submits `encoder`, copying `source` (unless it is already mappable, `mappable`) into a
    /// mappable buffer, waits, and returns its bytes.
    fn read_back(
        &self,
        mut encoder: wgpu::CommandEncoder,
        source: &wgpu::Buffer,
        size: u64,
        mappable: Option<wgpu::Buffer>,
    ) -> Result<Vec<u8>, RenderError> {
        let staging = match mappable {
            Some(b) => b,
            None => {
                let b = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("staging"),
                    size,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                });
                encoder.copy_buffer_to_buffer(source, 0, &b, 0, size);
                b
            }
        };
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Device(e.to_string()))?;
        rx.recv()
            .map_err(|e| RenderError::Device(e.to_string()))?
            .map_err(|e| RenderError::Device(e.to_string()))?;
        let bytes = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| RenderError::Device(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(bytes)
    }
}

fn check_size(opts: &RenderOptions) -> Result<(), RenderError> {
    let max = super::MAX_IMAGE_SIDE;
    if opts.width == 0 || opts.height == 0 || opts.width > max || opts.height > max {
        return Err(RenderError::Size(opts.width, opts.height, max));
    }
    Ok(())
}

fn unit(a: Vec3) -> Vec3 {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

fn uv_bounds(uv: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for t in uv {
        for c in 0..2 {
            lo[c] = lo[c].min(t[c]);
            hi[c] = hi[c].max(t[c]);
        }
    }
    if lo[0] > hi[0] {
        ([0.0; 2], [0.0; 2])
    } else {
        (lo, hi)
    }
}
