// The counter-based generator of cpu/src/sampling.rs, bit for bit: every
// uniform number is a pure function of (seed key, pixel, sample, index), so
// the GPU draws exactly the numbers the CPU draws for the same sample.
#ifndef GLINT_INTEGRATOR_RNG_GLSL
#define GLINT_INTEGRATOR_RNG_GLSL

// Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT 9(3), 2020.
uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

struct Rng {
    uint pixel;
    uint sample_index;
    uint key;
    uint block;
    uvec4 buf;
    uint used;
};

Rng rng_new(uint key, uint pixel, uint sample_index) {
    Rng r;
    r.pixel = pixel;
    r.sample_index = sample_index;
    r.key = key;
    r.block = 0u;
    r.buf = uvec4(0u);
    r.used = 4u;
    return r;
}

uint rng_next_u32(inout Rng r) {
    if (r.used == 4u) {
        r.buf = pcg4d(uvec4(r.pixel, r.sample_index, r.block, r.key));
        r.block += 1u;
        r.used = 0u;
    }
    uint x = r.buf[r.used];
    r.used += 1u;
    return x;
}

// Uniform in [0, 1): the top 24 bits, exactly representable.
float rng_next_f32(inout Rng r) {
    return float(rng_next_u32(r) >> 8u) * (1.0 / 16777216.0);
}

vec2 rng_next_2d(inout Rng r) {
    float x = rng_next_f32(r);
    float y = rng_next_f32(r);
    return vec2(x, y);
}

#endif
