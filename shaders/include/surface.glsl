// Surfaces as usdview's Storm shades them (OpenUSD 25.08; docs/method.md "Shading"):
//   - UsdPreviewSurface (usdShaders/shaders/previewSurface.glslfx): diffuse / pi, a GGX
//     lobe with Schlick's Fresnel, the metallic or specular workflow, clearcoat,
//     occlusion, emission, opacity;
//   - the fallback surface of a mesh without one (hdSt fallbackMaterialNetwork with
//     glf simpleLighting): displayColor x Lambert / 3.1415 plus a faint Blinn lobe.
// Lights are what scene/lights.py makes: a point or a direction with a colour
// (diffuse and specular), a 1/d^2 falloff and a spot cone; dome lights as SH9.
// Everything here is in world space; Storm works in eye space, which differs only by a
// rotation.

uniform int u_num_lights;
uniform vec4 u_light_position[MAX_LIGHTS];    // w 0: unit vector towards the light; 1: position
uniform vec3 u_light_diffuse[MAX_LIGHTS];
uniform vec3 u_light_specular[MAX_LIGHTS];
uniform vec3 u_light_ambient[MAX_LIGHTS];
uniform int u_light_attenuate[MAX_LIGHTS];    // 1/d^2
uniform vec4 u_light_spot[MAX_LIGHTS];        // xyz: cone axis (world); w: cone angle, degrees
uniform float u_light_spot_falloff[MAX_LIGHTS];
// DOME (a switch): a dome light, its SH9 radiance (x its colour)
uniform vec3 u_dome_sh[9];
// a textured dome's environment (lat-long, mip-mapped) for its specular reflections
layout(binding = DRAW_DOME_TEXTURE) uniform sampler2D u_dome_texture;
uniform int u_dome_textured;
uniform float u_dome_levels;                  // its mip levels - 1
uniform mat3 u_world_to_dome;
uniform vec3 u_dome_specular;                 // the dome's colour (specular)
uniform vec3 u_viewer_direction;              // the camera's backward axis (a directional viewer)

struct PreviewSurface {
    vec3 diffuse_color;
    vec3 emissive_color;
    bool use_specular_workflow;
    vec3 specular_color;
    float metallic;
    float roughness;
    float clearcoat;
    float clearcoat_roughness;
    float opacity;
    float ior;
    float occlusion;
};

#define STORM_EPSILON 0.001

float schlick_fresnel(float e_dot_h) {
    return pow(max(0.0, 1.0 - e_dot_h), 5.0);
}

float normal_distribution(float roughness, float n_dot_h) {
    float alpha = roughness * roughness;
    float alpha2 = alpha * alpha;
    float denom = n_dot_h * n_dot_h * (alpha2 - 1.0) + 1.0;
    return (alpha2 + STORM_EPSILON) / (PI * denom * denom);
}

float geometric(float roughness, float n_dot_l, float n_dot_e) {
    float k = roughness * roughness * 0.5;
    return n_dot_e / (n_dot_e * (1.0 - k) + k) * n_dot_l / (n_dot_l * (1.0 - k) + k);
}

vec3 direct_specular(vec3 f0, vec3 f90, float roughness, float fresnel, float n_dot_l,
                     float n_dot_e, float n_dot_h) {
    vec3 f = mix(f0, f90, fresnel);
    float d = normal_distribution(roughness, n_dot_h);
    float g = geometric(roughness, n_dot_l, n_dot_e);
    return f * g * d / (4.0 * n_dot_l * n_dot_e + STORM_EPSILON);
}

// the Fresnel reflectances at 0 and 90 degrees, and the diffuse colour they leave
void fresnel_terms(PreviewSurface s, out vec3 f0, out vec3 f90, out vec3 diffuse) {
    float r = (1.0 - s.ior) / (1.0 + s.ior);
    f0 = s.specular_color;
    f90 = vec3(1.0);
    diffuse = s.diffuse_color;
    if (!s.use_specular_workflow) {
        vec3 spec_color = mix(vec3(1.0), s.diffuse_color, s.metallic);
        f0 = mix(r * r * spec_color, spec_color, s.metallic);
        f90 = spec_color;
        diffuse *= 1.0 - s.metallic;  // pure metals have no diffuse
    }
}

// Storm's lightDistanceAttenuation x lightSpotAttenuation
float light_intensity(int i, vec3 p, vec3 l) {
    float atten = 1.0;
    if (u_light_position[i].w != 0.0 && u_light_attenuate[i] != 0) {
        vec3 d = u_light_position[i].xyz - p;
        atten = 1.0 / max(dot(d, d), 1e-30);
    }
    if (u_light_spot[i].w < 180.0) {
        float cos_light = dot(-l, u_light_spot[i].xyz);
        atten *= cos_light < cos(radians(u_light_spot[i].w)) ? 0.0 :
            (u_light_spot_falloff[i] > 0.0 ? pow(cos_light, u_light_spot_falloff[i]) : 1.0);
    }
    return atten;
}

vec3 light_direction(int i, vec3 p) {
    vec4 position = u_light_position[i];
    return position.w == 0.0 ? normalize(position.xyz) : normalize(position.xyz - p);
}

// SH9 at direction d, each band weighted (w0, w1, w2)
vec3 sh9(vec3 d, vec3 weights) {
    vec3 r = 0.282095 * weights.x * u_dome_sh[0];
    r += 0.488603 * weights.y * (d.y * u_dome_sh[1] + d.z * u_dome_sh[2] + d.x * u_dome_sh[3]);
    r += weights.z * (1.092548 * d.x * d.y * u_dome_sh[4] + 1.092548 * d.y * d.z * u_dome_sh[5]
                      + 0.315392 * (3.0 * d.z * d.z - 1.0) * u_dome_sh[6]
                      + 1.092548 * d.x * d.z * u_dome_sh[7]
                      + 0.546274 * (d.x * d.x - d.y * d.y) * u_dome_sh[8]);
    return max(r, vec3(0.0));
}

// Storm's domeLightBRDF (the split-sum scale and bias) by Karis' analytic fit
vec2 environment_brdf(float n_dot_e, float roughness) {
    vec4 r = roughness * vec4(-1.0, -0.0275, -0.572, 0.022) + vec4(1.0, 0.0425, 1.04, -0.04);
    float a004 = min(r.x * r.x, exp2(-9.28 * n_dot_e)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}

// the dome's radiance prefiltered for a roughness. Textured: its lat-long map at mip
// level roughness x levels, one level blurrier, with Storm's ProjectToLatLong (v = 0 at
// the top row). Storm samples a GGX-prefiltered map at roughness x levels; box-filtered
// mips one level up come closest to its wider lobe (a polished metal under a textured
// dome: corr 0.986 with Storm, against 0.976 at the same level; docs/method.md).
// Constant: the SH, from the raw radiance (a mirror) towards the cosine-convolved SH
// (irradiance / pi) as the lobe widens.
vec3 dome_prefiltered(vec3 r, float roughness) {
    if (u_dome_textured != 0) {
        vec3 d = normalize(u_world_to_dome * r);
        vec2 uv = vec2((atan(d.z, d.x) + 0.5 * PI) / (2.0 * PI),
                       1.0 - acos(clamp(d.y, -1.0, 1.0)) / PI);
        float lod = min(roughness * u_dome_levels + 1.0, u_dome_levels);
        return textureLod(u_dome_texture, uv, lod).rgb * u_dome_specular;
    }
    return sh9(r, vec3(1.0, mix(1.0, 2.0 / 3.0, roughness), mix(1.0, 0.25, roughness)));
}

// UsdPreviewSurface lit by every light (previewSurface.glslfx: evaluateLights)
vec3 preview_surface(PreviewSurface s, vec3 p, vec3 n, vec3 e) {
    float n_dot_e = max(0.0, dot(n, e));
    float roughness = max(0.001, s.roughness);
    float clearcoat_roughness = max(0.001, s.clearcoat_roughness);
    float r = (1.0 - s.ior) / (1.0 + s.ior);
    vec3 f0, f90, diffuse;
    fresnel_terms(s, f0, f90, diffuse);
    vec3 direct = vec3(0.0);
    for (int i = 0; i < u_num_lights && i < MAX_LIGHTS; ++i) {
        vec3 l = light_direction(i, p);
        vec3 h = normalize(e + l);
        float n_dot_l = max(0.0, dot(n, l));
        float n_dot_h = max(0.0, dot(n, h));
        float fresnel = schlick_fresnel(max(0.0, dot(e, h)));
        float intensity = light_intensity(i, p, l);
        vec3 d = diffuse / PI;
        vec3 s1 = direct_specular(f0, f90, roughness, fresnel, n_dot_l, n_dot_e, n_dot_h);
        d *= 1.0 - mix(f0, f90, fresnel);  // less diffuse at grazing angles
        vec3 s2 = vec3(0.0);
        if (s.clearcoat > 0.0) {
            s2 = s.clearcoat * direct_specular(vec3(r * r), vec3(1.0), clearcoat_roughness,
                                               fresnel, n_dot_l, n_dot_e, n_dot_h);
        }
        direct += s.occlusion * n_dot_l * intensity *
            (d * u_light_diffuse[i] + (s1 + s2) * u_light_specular[i]);
    }
    vec3 indirect = vec3(0.0);
#if defined DOME
    {  // evaluateIndirectLighting: its half vector is e itself
        vec3 reflected = reflect(-e, n);
        vec2 brdf = environment_brdf(n_dot_e, roughness);
        indirect = diffuse * (1.0 - f0) * sh9(n, vec3(1.0, 2.0 / 3.0, 0.25))
                 + dome_prefiltered(reflected, roughness) * (f0 * brdf.x + brdf.y);
        if (s.clearcoat > 0.0) {
            vec2 coat = environment_brdf(n_dot_e, clearcoat_roughness);
            indirect += dome_prefiltered(reflected, clearcoat_roughness) *
                (s.clearcoat * r * r * coat.x + coat.y);
        }
        indirect *= s.occlusion;
    }
#endif
    return s.emissive_color + direct + indirect;
}

// Storm's fallback surface: simpleLightingMaterial with usdview's default material
// (ambient 0.2, specular 0.1, shininess 32), the scene ambient 0.01, PI as 3.1415
vec3 fallback_surface(vec3 color, vec3 p, vec3 n) {
    const float storm_pi = 3.1415;
    vec3 ambient = vec3(0.0), diffuse = vec3(0.0), specular = vec3(0.0);
    for (int i = 0; i < u_num_lights && i < MAX_LIGHTS; ++i) {
        vec3 l = light_direction(i, p);
        vec3 h = normalize(l + u_viewer_direction);  // a directional viewer
        float atten = light_intensity(i, p, l);
        ambient += atten * u_light_ambient[i];
        diffuse += atten * max(0.0, dot(n, l)) * u_light_diffuse[i] / storm_pi;
        specular += atten * pow(max(0.0, dot(n, h)), 32.0) * u_light_specular[i] / storm_pi;
    }
#if defined DOME
    diffuse += sh9(n, vec3(1.0, 2.0 / 3.0, 0.25));
#endif
    return vec3(0.01 * 0.2) + ambient * 0.2 + diffuse * color + specular * 0.1;
}
