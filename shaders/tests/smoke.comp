#version 460
// Smoke kernel for the host plumbing: c[i] = a[i] + b[i] * scale, and a
// per-invocation counter added atomically (exercises read-modify-write of an
// output that was uploaded with initial contents).
layout(local_size_x = 64) in;

layout(std430, set = 0, binding = 0) readonly buffer A { float a[]; };
layout(std430, set = 0, binding = 1) readonly buffer B { float b[]; };
layout(std430, set = 0, binding = 2) buffer C { float c[]; };
layout(std430, set = 0, binding = 3) buffer Count { uint count; };

layout(push_constant) uniform Push {
    uint n;
    float scale;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n) {
        return;
    }
    c[i] = a[i] + b[i] * scale;
    atomicAdd(count, 1u);
}
