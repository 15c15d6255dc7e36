// Orthonormal shading frames, twin of cpu/src/frame.rs (normal on +z).
#ifndef GLINT_INTEGRATOR_FRAME_GLSL
#define GLINT_INTEGRATOR_FRAME_GLSL

struct Frame {
    vec3 s;
    vec3 t;
    vec3 n;
};

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited".
Frame frame_from_normal(vec3 n) {
    // copysign(1, n.z), -0 included, as Rust's f32::copysign.
    float sign_z = uintBitsToFloat(floatBitsToUint(1.0) | (floatBitsToUint(n.z) & 0x80000000u));
    float a = -1.0 / (sign_z + n.z);
    float b = n.x * n.y * a;
    Frame f;
    f.s = vec3(1.0 + sign_z * n.x * n.x * a, sign_z * b, -sign_z * n.x);
    f.t = vec3(b, sign_z + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}

// s follows the tangent projected on the tangent plane (Gram-Schmidt);
// the normal-only frame when the tangent is degenerate.
Frame frame_from_normal_tangent(vec3 n, vec3 tangent) {
    vec3 s = tangent - n * dot(n, tangent);
    float len2 = dot(s, s);
    if (!(len2 > 1e-12) || isinf(len2) || isnan(len2)) {
        return frame_from_normal(n);
    }
    Frame f;
    f.s = s / sqrt(len2);
    f.t = cross(n, f.s);
    f.n = n;
    return f;
}

vec3 frame_to_local(Frame f, vec3 v) {
    return vec3(dot(v, f.s), dot(v, f.t), dot(v, f.n));
}

vec3 frame_to_world(Frame f, vec3 v) {
    return f.s * v.x + f.t * v.y + f.n * v.z;
}

#endif
