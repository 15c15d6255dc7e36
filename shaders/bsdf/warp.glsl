// Square-to-domain warps: twin of cpu/src/bsdf/warp.rs.
#ifndef GLINT_BSDF_WARP_GLSL
#define GLINT_BSDF_WARP_GLSL

#include "glint_abi.glsl" // generated from cpu/src/abi.rs

vec2 square_to_concentric_disk(vec2 u) {
    vec2 o = 2.0 * u - vec2(1.0);
    if (o.x == 0.0 && o.y == 0.0) {
        return vec2(0.0);
    }
    float r;
    float theta;
    if (abs(o.x) > abs(o.y)) {
        r = o.x;
        theta = 0.25 * GLINT_PI * (o.y / o.x);
    } else {
        r = o.y;
        theta = 0.5 * GLINT_PI - 0.25 * GLINT_PI * (o.x / o.y);
    }
    return vec2(r * cos(theta), r * sin(theta));
}

vec3 square_to_cosine_hemisphere(vec2 u) {
    vec2 d = square_to_concentric_disk(u);
    float z = sqrt(max(1.0 - d.x * d.x - d.y * d.y, 0.0));
    return vec3(d.x, d.y, z);
}

#endif
