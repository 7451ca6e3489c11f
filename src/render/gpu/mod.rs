//! The wgpu renderer: a headless device, the limit-evaluation compute pipeline
//! (`shaders/limit_eval.wgsl`) and the ground, shadow and cloth pipelines (`shaders/cloth.wgsl`),
//! drawn 4× multisampled into an RGBA8 target that is read back.

use super::tessellate::{bounds, Tessellation};
use super::{Image, RenderError, RenderMesh, RenderOptions};
use crate::Vec3;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

mod device;
mod draw;

use draw::Draw;

const LIMIT_EVAL: &str = include_str!("../../../shaders/limit_eval.wgsl");
const CLOTH: &str = include_str!("../../../shaders/cloth.wgsl");
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

impl Renderer {
    /// Opens the first adapter wgpu finds (a software one if that is all there is).
    pub fn new() -> Result<Self, RenderError> {
        let (device, queue, name) = device::open()?;
        // errors are caught by error scopes; one that escapes them is reported, not a panic
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            eprintln!("GPU error: {e}");
        }));
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let (eval_module, cloth_module) = device::shader_modules(&device);
        let (eval_layout, eval) = device::eval_pipeline(&device, &eval_module);
        let pipelines = device::draw_pipelines(&device, &cloth_module);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Device(e.to_string()));
        }
        Ok(Self {
            device,
            queue,
            adapter: name,
            eval_layout,
            eval,
            frame_layout: pipelines.frame_layout,
            ground: pipelines.ground,
            shadow: pipelines.shadow,
            cloth: pipelines.cloth,
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
