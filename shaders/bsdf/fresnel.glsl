// Fresnel reflectance: line-for-line twin of cpu/src/bsdf/fresnel.rs (same
// function names; see the Rust side for the derivations and citations).
#ifndef GLINT_BSDF_FRESNEL_GLSL
#define GLINT_BSDF_FRESNEL_GLSL

// (R_s, R_p) at a dielectric interface; cos_i against +z, eta = n_in / n_out,
// cos_i < 0 means arriving from inside. Both 1 beyond the critical angle.
vec2 fresnel_dielectric_polarized(float cos_i, float eta) {
    cos_i = clamp(cos_i, -1.0, 1.0);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    float sin2_i = max(1.0 - cos_i * cos_i, 0.0);
    float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0) {
        return vec2(1.0, 1.0);
    }
    float cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    float r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return vec2(r_s * r_s, r_p * r_p);
}

float fresnel_dielectric(float cos_i, float eta) {
    vec2 r = fresnel_dielectric_polarized(cos_i, eta);
    return 0.5 * (r.x + r.y);
}

// Conductor with complex IOR eta + i k, one channel, cos_i in [0, 1].
float fresnel_conductor_channel(float cos_i, float eta, float k) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float cos2 = cos_i * cos_i;
    float sin2 = max(1.0 - cos2, 0.0);
    float eta2 = eta * eta;
    float k2 = k * k;
    float t0 = eta2 - k2 - sin2;
    float a2b2 = sqrt(max(t0 * t0 + 4.0 * eta2 * k2, 0.0));
    float a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
    float t1 = a2b2 + cos2;
    float t2 = 2.0 * a * cos_i;
    float denom_s = t1 + t2;
    if (denom_s <= 0.0) {
        return 1.0;
    }
    float rs = (t1 - t2) / denom_s;
    float t3 = cos2 * a2b2 + sin2 * sin2;
    float t4 = t2 * sin2;
    float denom_p = t3 + t4;
    float rp = denom_p > 0.0 ? rs * (t3 - t4) / denom_p : rs;
    return 0.5 * (rs + rp);
}

vec3 fresnel_conductor(float cos_i, vec3 eta, vec3 k) {
    return vec3(fresnel_conductor_channel(cos_i, eta.x, k.x),
                fresnel_conductor_channel(cos_i, eta.y, k.y),
                fresnel_conductor_channel(cos_i, eta.z, k.z));
}

// Refract w (pointing away, either side) through the interface with normal n
// and relative IOR eta = n_in / n_out; false under total internal reflection.
// etap receives eta_t / eta_i.
bool refract_dir(vec3 w, vec3 n, float eta, out vec3 wt, out float etap) {
    float cos_i = dot(n, w);
    if (cos_i < 0.0) {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    float sin2_i = max(1.0 - cos_i * cos_i, 0.0);
    float sin2_t = sin2_i / (eta * eta);
    wt = vec3(0.0);
    etap = 1.0;
    if (sin2_t >= 1.0) {
        return false;
    }
    float cos_t = sqrt(max(1.0 - sin2_t, 0.0));
    wt = -w / eta + (cos_i / eta - cos_t) * n;
    etap = eta;
    return true;
}

// multiscatter.rs fresnel_conductor_avg: 2 int F mu dmu by 8-point
// Gauss-Legendre in x = mu^2.
vec3 fresnel_conductor_avg(vec3 eta, vec3 k) {
    const float X[4] = float[4](0.18343464, 0.5255324, 0.7966665, 0.9602899);
    const float W[4] = float[4](0.3626838, 0.31370664, 0.22238103, 0.10122854);
    vec3 s = vec3(0.0);
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 2; j++) {
            float sgn = j == 0 ? -1.0 : 1.0;
            float x = 0.5 + 0.5 * sgn * X[i];
            s += W[i] * 0.5 * fresnel_conductor(sqrt(x), eta, k);
        }
    }
    return s;
}

#endif
