// Spherical triangles: solid angle and uniform sampling (Arvo 1995, as
// pbrt-v4 writes it), twin of cpu/src/spherical.rs (same names, same
// operations; read it for the derivation).
#ifndef GLINT_INTEGRATOR_SPHERICAL_GLSL
#define GLINT_INTEGRATOR_SPHERICAL_GLSL

#include "glint_abi.glsl" // ATAN_*, SPHERICAL_SAMPLING_*: generated from cpu/src/abi.rs

#define SPH_PI 3.14159265358979323846

vec3 sph_normalize_or_zero(vec3 v) {
    float l2 = dot(v, v);
    return l2 > 0.0 ? v * inversesqrt(l2) : vec3(0.0);
}

// glint_cpu::spherical::atan2_nonneg: atan(y / x) for y >= 0 by Cephes'
// atanf, not GLSL's atan (which Vulkan holds only to 4096 ulp).
float atan2_nonneg(float y, float x) {
    bool flip = x < 0.0;
    float ax = abs(x);
    float base;
    float t;
    if (y > ATAN_TAN_3PI_8 * ax) {
        base = 1.57079632679489661923;
        t = -ax / y;
    } else if (y > ATAN_TAN_PI_8 * ax) {
        base = 0.78539816339744830962;
        t = (y - ax) / (y + ax);
    } else if (ax > 0.0) {
        base = 0.0;
        t = y / ax;
    } else {
        return 0.0;
    }
    float z = t * t;
    float r = base + (((ATAN_P9 * z + ATAN_P7) * z + ATAN_P5) * z + ATAN_P3) * z * t + t;
    return flip ? SPH_PI - r : r;
}

// Solid angle of triangle (v0, v1, v2) seen from p (van Oosterom and
// Strackee 1983), in [0, 2 pi] (0 when degenerate), and its shape: the
// solid angle over the longest chord squared (spherical_triangle_shape).
vec2 spherical_triangle_shape(vec3 v0, vec3 v1, vec3 v2, vec3 p) {
    vec3 a = sph_normalize_or_zero(v0 - p);
    vec3 b = sph_normalize_or_zero(v1 - p);
    vec3 c = sph_normalize_or_zero(v2 - p);
    float num = abs(dot(a, cross(b, c)));
    float den = 1.0 + dot(a, b) + dot(b, c) + dot(c, a);
    float omega = 2.0 * atan2_nonneg(num, den);
    if (isnan(omega) || isinf(omega)) {
        return vec2(0.0);
    }
    vec3 ab = a - b;
    vec3 bc = b - c;
    vec3 ca = c - a;
    float chord2 = max(dot(ab, ab), max(dot(bc, bc), dot(ca, ca)));
    return vec2(omega, chord2 > 0.0 ? omega / chord2 : 0.0);
}

// A direction uniform in the solid angle of the triangle from p, as the
// barycentrics (b1, b2) of the point it hits; false when degenerate.
// omega: the triangle's solid angle from p.
bool sample_spherical_triangle(vec3 v0, vec3 v1, vec3 v2, vec3 p, float omega, vec2 u,
                               out vec2 bary) {
    bary = vec2(0.0);
    vec3 a = sph_normalize_or_zero(v0 - p);
    vec3 b = sph_normalize_or_zero(v1 - p);
    vec3 c = sph_normalize_or_zero(v2 - p);
    vec3 n_ab = cross(a, b);
    vec3 n_ca = cross(c, a);
    vec3 n_bc = cross(b, c);
    if (dot(n_ab, n_ab) == 0.0 || dot(n_ca, n_ca) == 0.0 || dot(n_bc, n_bc) == 0.0) {
        return false;
    }
    n_ab = normalize(n_ab);
    n_ca = normalize(n_ca);
    float cos_alpha = -dot(n_ab, n_ca);
    float sin_alpha = length(cross(n_ab, n_ca));
    float sin_u = sin(u.x * omega);
    float cos_u = cos(u.x * omega);
    float sin_ap = -sin_u;
    float cos_ap = -cos_u;
    float sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
    float cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
    float k1 = cos_phi + cos_alpha;
    float k2 = sin_phi - sin_alpha * dot(a, b);
    float cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
                 / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    if (isnan(cos_bp)) {
        return false;
    }
    cos_bp = clamp(cos_bp, -1.0, 1.0);
    float sin_bp = sqrt(max(1.0 - cos_bp * cos_bp, 0.0));
    vec3 cp = cos_bp * a + sin_bp * sph_normalize_or_zero(c - dot(c, a) * a);
    vec3 cpb = cp - b;
    float one_minus_cos = u.y * 0.5 * dot(cpb, cpb);
    float cos_theta = 1.0 - one_minus_cos;
    float sin_theta = sqrt(max(one_minus_cos * (2.0 - one_minus_cos), 0.0));
    vec3 w = cos_theta * b + sin_theta * sph_normalize_or_zero(cp - dot(cp, b) * b);
    vec3 e1 = v1 - v0;
    vec3 e2 = v2 - v0;
    vec3 s1 = cross(w, e2);
    float divisor = dot(s1, e1);
    if (divisor == 0.0 || isinf(divisor) || isnan(divisor)) {
        return false;
    }
    float inv = 1.0 / divisor;
    vec3 s = p - v0;
    float b1 = clamp(dot(s, s1) * inv, 0.0, 1.0);
    float b2 = clamp(dot(w, cross(s, e1)) * inv, 0.0, 1.0);
    float sum = b1 + b2;
    bary = sum > 1.0 ? vec2(b1 / sum, b2 / sum) : vec2(b1, b2);
    return true;
}

// lights::spherical_sampling_angle: the solid angle when light sampling
// picks a point on triangle (v0, v1, v2) by solid angle from p, else 0 (by
// area). center, radius, area: the emitter's bounding sphere and area.
float spherical_sampling_angle(vec3 v0, vec3 v1, vec3 v2, vec3 center, float radius, float area,
                               vec3 p) {
    // Far for its size (omega <= area / d_min^2): by area, no solid angle.
    vec3 pc = p - center;
    float d2 = dot(pc, pc);
    float d_min = sqrt(d2) - radius;
    if (d2 > radius * radius && area < SPHERICAL_SAMPLING_MIN * d_min * d_min) {
        return 0.0;
    }
    // Nearly in the triangle's plane: by area (grazing directions).
    vec3 n = cross(v1 - v0, v2 - v0);
    vec3 f0 = v0 - p;
    vec3 f1 = v1 - p;
    vec3 f2 = v2 - p;
    float far2 = max(dot(f0, f0), max(dot(f1, f1), dot(f2, f2)));
    float height = abs(dot(n, p - v0));
    float n_len = length(n);
    if (!(height >= SPHERICAL_SAMPLING_HEIGHT * n_len * sqrt(far2))) {
        return 0.0;
    }
    // Too small for its height (omega <= height / (2 d^3), d the larger of
    // the plane's distance and d_min; lights.rs near_angle): by area, no
    // solid angle.
    float d = max(n_len > 0.0 ? height / n_len : 0.0, d_min);
    if (d > 0.0
        && height < 2.0 * SPHERICAL_SAMPLING_MIN * (1.0 - SOLID_ANGLE_BOUND_MARGIN) * (d * d * d)) {
        return 0.0;
    }
    vec2 s = spherical_triangle_shape(v0, v1, v2, p);
    return (s.x >= SPHERICAL_SAMPLING_MIN && s.x <= SPHERICAL_SAMPLING_MAX
            && s.y >= SPHERICAL_SAMPLING_SHAPE) ? s.x : 0.0;
}

#endif
