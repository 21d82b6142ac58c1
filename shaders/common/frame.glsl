// What every program of a frame shares — camera, exposure, time, sun and sky, the rain medium, the sun shadow and
// the lights — in ONE uniform block (rain_core/gfx/frame_block.py packs it, std140, once per view; bound at
// binding point 0). sky.glsl, lighting.glsl and atmosphere.glsl include this file: included once per program.
// The member order is the Python layout's (FRAME_BLOCK_LAYOUT); the tests read the block back through a shader.
// A program with a light list of its own (rainfall's drops: only the lights that reach its boxes, in its RainFrame
// block) defines FRAME_OWN_LIGHTS before including this file and declares u_light_count, u_light_pos,
// u_light_dir and u_light_color itself, before common/lighting.glsl reads them.
#define MAX_LIGHTS 32
layout(std140) uniform FrameBlock {
    mat4 u_view_proj;
    mat4 u_shadow_matrix;      // wrapped world → shadow map [0, 1]³
    vec3 u_camera_pos;         // m, wrapped frame
    float u_exposure;          // cd/m² → tone-mapper input
    vec3 u_sun_dir;            // towards the sun
    float u_time;              // s
    vec3 u_sun_illum;          // lux, perpendicular to the rays
    float u_night;             // 0 day … 1 night
    vec3 u_sky_zenith;         // cd/m²
    float u_ground_albedo;
    vec3 u_sky_horizon;        // cd/m²
    float u_extinction_per_m;  // 1/m, total: clear air + rain + haze
    vec3 u_airlight;           // cd/m², isotropic airlight (the surroundings' mean radiance)
    float u_medium_extinction_per_m;  // 1/m, the rain + haze share of β (0 in clear air)
    vec3 u_airlight_sun;       // lux: sun illuminance × (medium β / total β), weights the phase function
    float u_phase_g;           // Henyey–Greenstein asymmetry of the forward lobe (0 isotropic … 1 forward)
    vec3 u_airlight_sun_dir;   // unit, towards the sun
    float u_phase_back_g;      // asymmetry of the backward lobe (< 0)
    vec3 u_shadow_params;      // on (1/0), texel size (1/px), depth bias
    float u_phase_back_weight; // its weight (0: a single forward lobe)
#ifndef FRAME_OWN_LIGHTS
    int u_light_count;
    int u_light_grid_px;             // this view's light grid: tile size in pixels (0: none, every light everywhere)
    vec4 u_light_pos[MAX_LIGHTS];    // xyz m, w range m (negative: a low-beam headlight, see lighting.glsl)
    vec4 u_light_dir[MAX_LIGHTS];    // xyz unit, w cos(outer cone) (-1 = point light)
    vec4 u_light_color[MAX_LIGHTS];  // rgb = colour × intensity (cd), w cos(inner cone)
#endif
};
