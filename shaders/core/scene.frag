#version 330 core
// Opaque scene: world tile, vehicles, cabin. Output is pre-exposed HDR luminance.
#include "common/frame.glsl"
#include "common/lighting.glsl"
#include "common/light_grid.glsl"
#include "common/atmosphere.glsl"
#include "core/materials.glsl"
in vec3 v_world;
in vec3 v_normal;
in vec3 v_albedo;
in vec3 v_params;
uniform bool u_mirror_live;       // this draw is the door mirror glass and a mirror view was drawn
uniform sampler2D u_mirror_view;  // the scene reflected by the glass, pre-exposed (rain_core/gfx/mirrors.py)
uniform vec2 u_mirror_uv_scale;   // 1 / frame size in pixels: the view is addressed by screen position
const float MIRROR_REFLECTANCE = 0.5;  // rain_core/gfx/mirrors.py REFLECTANCE
out vec4 f_color;
void main() {
    if (u_mirror_live) {  // a plane mirror 0.7 m away: its picture is the reflected scene, already fogged and exposed
        f_color = vec4(MIRROR_REFLECTANCE * texture(u_mirror_view, gl_FragCoord.xy * u_mirror_uv_scale).rgb, 1.0);
        return;
    }
    use_light_grid();
    int material = int(v_params.z + 0.5);
    vec3 V = normalize(u_camera_pos - v_world);
    float dist = length(u_camera_pos - v_world);
    vec3 radiance;
    if (material == MAT_EMISSIVE) {
        radiance = v_albedo * EMISSIVE_NITS_PER_UNIT * mix(0.04, 1.0, u_night);
        radiance = emission_effects(v_albedo, radiance);
    } else {
        Surface s;
        s.position = v_world;
        s.normal = normalize(v_normal) * (gl_FrontFacing ? 1.0 : -1.0);
        s.albedo = v_albedo;
        s.roughness = clamp(v_params.x, 0.02, 1.0);
        s.metallic = v_params.y;
        s.f0 = 0.04;  // dielectrics (paint, glass, asphalt): IOR ≈ 1.5
        s.ambient_occlusion = 1.0;
        apply_surface_effects(s, material);
        radiance = shade_surface(s, V);
        radiance = finish_surface_effects(s, V, radiance);
    }
    radiance = apply_atmosphere_dir(radiance, dist, -V);
    // The HDR target is half float (largest 65504): a headlight's highlight seen on still water a few metres
    // away can pass that and would be stored as inf. Clamp below it; radiance is never negative.
    f_color = vec4(clamp(radiance * u_exposure, 0.0, 6.0e4), 1.0);
}
