//! Opening the wgpu device and compiling the renderer's kernels: the limit-evaluation compute
//! pipeline (`shaders/limit_eval.wgsl`) and the ground, shadow and cloth render pipelines
//! (`shaders/cloth.wgsl`), 4× multisampled.

use super::{Vertex, CLOTH, COLOR, DEPTH, LIMIT_EVAL, SAMPLES};
use crate::render::RenderError;

/// The first adapter wgpu finds (a software one if that is all there is), its device and queue,
/// and its name.
pub(super) fn open() -> Result<(wgpu::Device, wgpu::Queue, String), RenderError> {
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
    Ok((device, queue, name))
}

/// The compiled shaders: limit evaluation and cloth.
pub(super) fn shader_modules(device: &wgpu::Device) -> (wgpu::ShaderModule, wgpu::ShaderModule) {
    let eval_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("limit_eval.wgsl"),
        source: wgpu::ShaderSource::Wgsl(LIMIT_EVAL.into()),
    });
    let cloth_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("cloth.wgsl"),
        source: wgpu::ShaderSource::Wgsl(CLOTH.into()),
    });
    (eval_module, cloth_module)
}

/// The limit-evaluation pipeline and the layout of its bindings (four read-only storage
/// buffers, the output vertices and the parameters).
pub(super) fn eval_pipeline(
    device: &wgpu::Device,
    eval_module: &wgpu::ShaderModule,
) -> (wgpu::BindGroupLayout, wgpu::ComputePipeline) {
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
        module: eval_module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    (eval_layout, eval)
}

/// The render pipelines and the layout of their frame uniform.
pub(super) struct DrawPipelines {
    pub frame_layout: wgpu::BindGroupLayout,
    pub ground: wgpu::RenderPipeline,
    pub shadow: wgpu::RenderPipeline,
    pub cloth: wgpu::RenderPipeline,
}

/// The ground, shadow and cloth pipelines, sharing the frame uniform.
pub(super) fn draw_pipelines(
    device: &wgpu::Device,
    cloth_module: &wgpu::ShaderModule,
) -> DrawPipelines {
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
                module: cloth_module,
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
                module: cloth_module,
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
    DrawPipelines {
        frame_layout,
        ground,
        shadow,
        cloth,
    }
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

pub(super) fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRS,
    }
}

pub(super) fn uv_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: 8,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &UV_ATTRS,
    }
}
