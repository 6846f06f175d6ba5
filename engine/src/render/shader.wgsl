// The camera's only shader: diffuse shading under a fixed sun, exposure from the world's
// light, exponential fog toward the sky colour, z-depth in metres written as the bits of
// an f32 into an R32Uint target (renderable on every backend, GL included), and each pixel's
// label (class id | actor << 8) into a second R32Uint target.

struct Globals {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,      // camera position, world metres
    forward: vec4<f32>,  // optical axis, unit
    sun: vec4<f32>,      // direction toward the sun, unit
    sky: vec4<f32>,      // sky (and fog) colour at nominal exposure
    params: vec4<f32>,   // exposure, fog extinction 1/m, far clip m, unused
};

@group(0) @binding(0) var<uniform> g: Globals;

struct VertexIn {
    @location(0) pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) m0: vec4<f32>,
    @location(4) m1: vec4<f32>,
    @location(5) m2: vec4<f32>,
    @location(6) m3: vec4<f32>,
    @location(7) tint: vec4<f32>,
    @location(8) label: u32,
    @location(9) instance_label: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec3<f32>,
    @location(3) @interpolate(flat) label: u32,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    let model = mat4x4<f32>(v.m0, v.m1, v.m2, v.m3);
    let world = model * vec4<f32>(v.pos, 1.0);
    var out: VertexOut;
    out.clip = g.view_proj * world;
    out.world = world.xyz;
    out.normal = (model * vec4<f32>(v.normal, 0.0)).xyz;
    out.color = v.color * v.tint.rgb;
    out.label = v.label | v.instance_label;
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) depth: u32,
    @location(2) label: u32,
};

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let rel = in.world - g.eye.xyz;
    let z = dot(rel, g.forward.xyz);
    if (z > g.params.z) {
        discard;
    }
    let n = normalize(in.normal);
    let shade = 0.45 + 0.55 * max(dot(n, g.sun.xyz), 0.0);
    let lit = in.color * shade * g.params.x;
    // Koschmieder: the share of the object's own light left after `d` metres is exp(-σ d).
    let transmittance = exp(-g.params.y * length(rel));
    let color = mix(g.sky.rgb * g.params.x, lit, transmittance);
    var out: FragmentOut;
    out.color = vec4<f32>(color, 1.0);
    out.depth = bitcast<u32>(z);
    out.label = in.label;
    return out;
}
