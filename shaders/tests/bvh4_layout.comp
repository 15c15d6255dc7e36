#version 460
// Pins Bvh4Node (shaders/bvh_types.glsl) to glint_cpu::bvh::Bvh4Node: each
// node's fields, read by name, written out as 32 words in the Rust field
// order; tests/gpu_bvh.rs compares them with the node's bytes.
layout(local_size_x = 64) in;

#include "bvh_types.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Nodes { Bvh4Node nodes[]; };
layout(std430, set = 0, binding = 1) buffer Words { uint words[]; };

layout(push_constant) uniform Push {
    uint node_count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.node_count) {
        return;
    }
    Bvh4Node n = nodes[i];
    uvec4 w[8] = uvec4[8](floatBitsToUint(n.lo_x), floatBitsToUint(n.hi_x), floatBitsToUint(n.lo_y),
                          floatBitsToUint(n.hi_y), floatBitsToUint(n.lo_z), floatBitsToUint(n.hi_z),
                          n.child, n.pad);
    for (uint k = 0u; k < 8u; k++) {
        for (uint j = 0u; j < 4u; j++) {
            words[32u * i + 4u * k + j] = w[k][j];
        }
    }
}
