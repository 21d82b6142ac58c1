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

int g_material = MAT_GENERIC;  // the material being shaded (set by apply_surface_effects)

// Hook where surface effects change a material before lighting (the wet road). Dry: unchanged.
void apply_surface_effects(inout Surface s, int material) {
    g_material = material;
    road_wet_surface(s, material);
}

// Road signs (paint above the road, rain_core/world/kerbside.py) are retroreflective sheeting: a light close to
// the line of sight sends back R_A(α)·E (cd/m²), α the observation angle between the directions to the light and
// to the eye, E the light's illuminance on a plane facing it (lux), times the entrance-angle falloff. R_A of white
// sheeting (cd/lx/m²): ~250 at 0.2° falling to ~5 at 2–3° (EN 12899-1 class RA2-like), here a fit of two
// exponentials; a colour returns its share (albedo / white 0.8). A Lambertian white returns only 0.25.
vec3 sign_retroreflection(Surface s, vec3 V) {
    if (g_material != MAT_PAINT || s.position.y < 0.5) return vec3(0.0);
    vec3 sum = vec3(0.0);
    for (uint m = light_mask(); m != 0u;) {
        int i = pop_bit(m);
        vec3 L, E;
        if (!light_at(i, s.position, L, E)) continue;
        float alpha = degrees(acos(clamp(dot(L, V), -1.0, 1.0)));
        if (alpha > 8.0) continue;
        float ra = 300.0 * exp(-alpha / 0.45) + 15.0 * exp(-alpha / 2.0);
        if (u_light_pos[i].w < 0.0) {
            // A low beam sends ~1/10 of its peak above the horizon (ECE R112: ≤ 625 cd in zone III, more on the
            // kerb side to light signs); spot_factor shapes only the road below.
            float up_deg = degrees(asin(clamp(-L.y, -1.0, 1.0)));
            E *= mix(1.0, 0.1, smoothstep(-0.5, 1.0, up_deg));
        }
        sum += ra * max(dot(s.normal, L), 0.0) * E;
    }
    return sum * s.albedo / 0.8 * u_direct_scale;
}

// Hook after lighting: a water layer over the shaded surface (cd/m²), the signs' retroreflection. Dry, no sign:
// unchanged.
vec3 finish_surface_effects(Surface s, vec3 V, vec3 radiance) {
    return road_water_layer(s, V, radiance) + sign_retroreflection(s, V);
}

// Hook for emissive surfaces (cd/m²). Unchanged except in the road's reflection pass.
vec3 emission_effects(vec3 emissive_albedo, vec3 radiance) {
    return road_emission(emissive_albedo, radiance);
}
