#version 330 core
// Label images, geometry pass: distance along the view ray (m), class id and, on the road, the water region the
// road effect shades there (0 dry, 1 wet, 2 drenched, 3 puddle; 255 off the road). The region follows
// road_wet_surface / road_water_layer's debug colours in road/surface.glsl, from the same film model (film.glsl,
// bound by RoadEffect.bind_film_uniforms); rain_core.effects.road.surface.road_regions is its NumPy twin.
// Defines: CLASS_ROAD, CLASS_MARKING (rain_core.labels.classes.CLASS_IDS).
#include "common/frame.glsl"
#include "road/film.glsl"
uniform float u_label_road;  // 1: the road effect is active and its film uniforms are bound; 0: a dry road
in vec3 v_world;
flat in float v_class;
out vec4 f_label;

const float WET_MIN = 0.02;  // wetness below this is dry (rain_core.effects.road.surface.WET_MIN)

float road_region(vec2 xz) {
    if (u_label_road < 0.5 || abs(xz.x) > ROAD_HALF_WIDTH_M) return 0.0;
    float standing = road_water_depths_mm(xz).x;
    float cover = clamp(standing / MACROTEXTURE_MM, 0.0, 1.0);
    float wet = u_road_levels.x * (1.0 - road_maps(xz).g);
    return cover >= 1.0 ? 3.0 : (cover > 0.0 ? 2.0 : (wet >= WET_MIN ? 1.0 : 0.0));
}

void main() {
    int cls = int(v_class + 0.5);
    float region = (cls == CLASS_ROAD || cls == CLASS_MARKING) ? road_region(v_world.xz) : 255.0;
    f_label = vec4(length(v_world - u_camera_pos), v_class, region, 0.0);
}
