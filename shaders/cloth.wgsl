// Drawing cloth: the ground plane, the cloth's shadow projected on it along the light, and the
// cloth itself, lit from one direction (two-sided) with its warp yarns (lines of constant v,
// red) and weft yarns (lines of constant u, blue) drawn every `lines.x` metres of fabric, so that
// stretch spreads the lines and shear turns their right angles (Clyde et al. 2017, Figure 5).
// Lines are antialiased with screen-space derivatives and `lines.y` pixels wide.

struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    // unit vector towards the light
    light: vec4<f32>,
    // rgb; a = 1 draws the yarn lines
    cloth: vec4<f32>,
    // x: line spacing (m of fabric), y: line width (px)
    lines: vec4<f32>,
    // x: height of the ground plane
    ground: vec4<f32>,
    // xmin, ymin, xmax, ymax of the ground
    ground_rect: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

const WARP = vec3<f32>(0.70, 0.16, 0.10);
const WEFT = vec3<f32>(0.10, 0.26, 0.70);
const GROUND = vec3<f32>(0.88, 0.88, 0.86);
const SHADOW = vec3<f32>(0.66, 0.66, 0.65);

struct ClothOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_cloth(
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) uv: vec2<f32>,
) -> ClothOut {
    var out: ClothOut;
    out.clip = frame.view_proj * vec4<f32>(position.xyz, 1.0);
    out.world = position.xyz;
    out.normal = normal.xyz;
    out.uv = uv;
    return out;
}

@fragment
fn fs_cloth(v: ClothOut) -> @location(0) vec4<f32> {
    let g = v.uv / frame.lines.x;
    let w = max(fwidth(g), vec2<f32>(1e-6));
    // pixels from the nearest line of constant u (x) and of constant v (y)
    let d = abs(fract(g + 0.5) - 0.5) / w;
    let cover = clamp(vec2<f32>(0.5 * frame.lines.y + 0.5) - d, vec2<f32>(0.0), vec2<f32>(1.0))
        * frame.cloth.a;
    var base = mix(frame.cloth.rgb, WEFT, cover.x);
    base = mix(base, WARP, cover.y);
    let to_eye = normalize(frame.eye.xyz - v.world);
    var n = normalize(v.normal);
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    let diffuse = max(dot(n, frame.light.xyz), 0.0);
    let h = normalize(frame.light.xyz + to_eye);
    let spec = 0.06 * pow(max(dot(n, h), 0.0), 24.0);
    return vec4<f32>(base * (0.38 + 0.62 * diffuse) + vec3<f32>(spec), 1.0);
}

@vertex
fn vs_shadow(@location(0) position: vec4<f32>) -> @builtin(position) vec4<f32> {
    // the light travels along −light; follow it from the point down to the ground
    let dir = -frame.light.xyz;
    let t = (frame.ground.x - position.z) / dir.z;
    let p = position.xyz + t * dir;
    return frame.view_proj * vec4<f32>(p.xy, frame.ground.x, 1.0);
}

@fragment
fn fs_shadow() -> @location(0) vec4<f32> {
    return vec4<f32>(SHADOW, 1.0);
}

@vertex
fn vs_ground(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let r = frame.ground_rect;
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(r.x, r.y), vec2<f32>(r.z, r.y), vec2<f32>(r.z, r.w),
        vec2<f32>(r.x, r.y), vec2<f32>(r.z, r.w), vec2<f32>(r.x, r.w),
    );
    return frame.view_proj * vec4<f32>(corners[i], frame.ground.x, 1.0);
}

@fragment
fn fs_ground() -> @location(0) vec4<f32> {
    return vec4<f32>(GROUND, 1.0);
}
