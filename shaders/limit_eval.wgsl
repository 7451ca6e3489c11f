// Catmull–Clark limit evaluation on the GPU: one invocation per sample of a tessellation applies
// that sample's stencil (control indices and weights for x, x_u and x_v; see src/subdiv and
// src/render/tessellate.rs) to the control points, and writes the limit position and unit
// normal x_u × x_v / |x_u × x_v| as a vertex the cloth shader draws. The CPU stencils in f64 are
// its oracle (tests/render.rs).

struct Vertex {
    position: vec4<f32>,
    normal: vec4<f32>,
}

struct Params {
    num_points: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<storage, read> control: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> offsets: array<u32>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read> weights: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> vertices: array<Vertex>;
@group(0) @binding(5) var<uniform> params: Params;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let q = id.x;
    if (q >= params.num_points) {
        return;
    }
    var x = vec3<f32>(0.0);
    var xu = vec3<f32>(0.0);
    var xv = vec3<f32>(0.0);
    for (var k = offsets[q]; k < offsets[q + 1u]; k = k + 1u) {
        let p = control[indices[k]].xyz;
        let w = weights[k];
        x = x + w.x * p;
        xu = xu + w.y * p;
        xv = xv + w.z * p;
    }
    let n = cross(xu, xv);
    let l = length(n);
    var normal = vec3<f32>(0.0, 0.0, 1.0);
    if (l > 0.0) {
        normal = n / l;
    }
    vertices[q] = Vertex(vec4<f32>(x, 1.0), vec4<f32>(normal, 0.0));
}
