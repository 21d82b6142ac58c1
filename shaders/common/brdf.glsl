// Cook–Torrance with GGX: Walter et al. 2007 distribution, Heitz 2014 height-correlated Smith visibility,
// Schlick Fresnel. Roughness is perceptual (alpha = roughness²).
const float PI = 3.14159265358979;

float D_GGX(float NoH, float alpha) {
    float a2 = alpha * alpha;
    float d = NoH * NoH * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float V_SmithGGXCorrelated(float NoV, float NoL, float alpha) {
    float a2 = alpha * alpha;
    float gv = NoL * sqrt(NoV * NoV * (1.0 - a2) + a2);
    float gl = NoV * sqrt(NoL * NoL * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-5);
}

vec3 F_Schlick(vec3 f0, float VoH) {
    return f0 + (1.0 - f0) * pow(clamp(1.0 - VoH, 0.0, 1.0), 5.0);  // VoH may round above 1: pow(<0) is NaN
}

// Split-sum environment BRDF, analytic fit (Karis 2014, "Physically Based Shading on Mobile").
vec3 env_brdf_approx(vec3 f0, float roughness, float NoV) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = roughness * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * NoV)) * r.x + r.y;
    vec2 ab = vec2(-1.04, 1.04) * a004 + r.zw;
    return max(f0 * ab.x + ab.y, 0.0);  // the fit dips below 0 for rough surfaces with f0 ≲ 0.005 (wet asphalt)
}

// Radiance reflected towards V from a light of illuminance E (perpendicular to L).
vec3 brdf_direct(vec3 N, vec3 V, vec3 L, vec3 diffuse_color, vec3 f0, float roughness) {
    float NoL = dot(N, L);
    if (NoL <= 0.0) return vec3(0.0);
    vec3 H = normalize(V + L);
    float NoV = max(dot(N, V), 1e-4);
    float NoH = max(dot(N, H), 0.0);
    float VoH = max(dot(V, H), 0.0);
    float alpha = max(roughness * roughness, 0.002);
    vec3 F = F_Schlick(f0, VoH);
    vec3 spec = D_GGX(NoH, alpha) * V_SmithGGXCorrelated(NoV, NoL, alpha) * F;
    return (diffuse_color * (1.0 - F) / PI + spec) * NoL;
}
