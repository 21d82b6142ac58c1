// Material ids: keep in sync with rain_core/mesh.py.
#define MAT_GENERIC 0
#define MAT_ASPHALT 1
#define MAT_PAINT 2
#define MAT_CONCRETE 3
#define MAT_METAL 4
#define MAT_GLASS 5
#define MAT_FOLIAGE 6
#define MAT_EMISSIVE 7
#define MAT_CAR_PAINT 8
#define MAT_RUBBER 9
// Emissive albedo is radiance in W/(sr·m²) at 555 nm; × 683 lm/W gives luminance in cd/m² (rain_core/mesh.py).
const float EMISSIVE_NITS_PER_UNIT = 683.0;

#include "road/surface.glsl"

// Hook where surface effects change a material before lighting (the wet road). Dry: unchanged.
void apply_surface_effects(inout Surface s, int material) {
    road_wet_surface(s, material);
}

// Hook after lighting: a water layer over the shaded surface (cd/m²). Dry: unchanged.
vec3 finish_surface_effects(Surface s, vec3 V, vec3 radiance) {
    return road_water_layer(s, V, radiance);
}

// Hook for emissive surfaces (cd/m²). Unchanged except in the road's reflection pass.
vec3 emission_effects(vec3 emissive_albedo, vec3 radiance) {
    return road_emission(emissive_albedo, radiance);
}
