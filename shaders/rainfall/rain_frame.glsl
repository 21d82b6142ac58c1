// The rainfall's per-frame uniform block (rain_core/effects/rainfall/rain_block.py packs it, std140; bound at
// RAIN_FRAME_BINDING), for the streak and splash programs alike: one buffer write a frame instead of a dozen
// uniform writes into each program. drop.glsl includes it before common/lighting.glsl, which reads the lights.
#ifndef LAYERS
#define LAYERS 4
#endif
#define RAIN_MAX_VEHICLES 8            // constants.MAX_VEHICLES
#ifndef MAX_LIGHTS
#define MAX_LIGHTS 32                  // common/frame.glsl's (the debug probe includes no frame.glsl)
#endif
layout(std140) uniform RainFrame {
    vec3 u_box_lo[LAYERS];         // m, wrapped frame
    vec3 u_box_off[LAYERS];        // m: (∫wind − lo) mod ext (x, z); (BOX_BOTTOM − lo_y) mod height (y)
    vec3 u_box_turb[LAYERS];       // m: TURB_EPS·∫wind mod ext (x, z)
    vec4 u_veh_pose[RAIN_MAX_VEHICLES];  // x, y, z (wrapped frame), yaw
    vec3 u_wind;                   // m/s
    int u_time_whole;              // s, floor(t mod RAIN_TIME_PERIOD)
    float u_time_frac;             // s, the rest
    uint u_epoch;                  // floor(t / RAIN_TIME_PERIOD) mod 2^32
    vec3 u_splash_lo;              // m, wrapped frame (splash.vert)
    uint u_splash_count;           // whole splash periods of t, mod 2^32
    vec3 u_splash_off;             // m, (−lo) mod ext in the world frame (x, z)
    float u_splash_tau;            // the fraction
    vec3 u_cam_vel;                // m/s, world (streak_record.vert)
    // The lights that reach the boxes (effect.py _lights), as common/lighting.glsl reads them (frame.glsl's
    // members of the same names): they change with the frame too.
    int u_light_count;
    vec4 u_light_pos[MAX_LIGHTS];
    vec4 u_light_dir[MAX_LIGHTS];
    vec4 u_light_color[MAX_LIGHTS];
};
