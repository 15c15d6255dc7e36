// Owen-scrambled Sobol pairs and the path's sampler: cpu/src/sobol.rs bit
// for bit (read its header for the construction). The scramble, hash and
// float conversion are the crate sobol_burley's (0.5), function by
// function; tests/gpu_sobol.rs pins every (seed, pixel, sample, dimension)
// to the Rust.
#ifndef GLINT_INTEGRATOR_SOBOL_GLSL
#define GLINT_INTEGRATOR_SOBOL_GLSL

#include "rng.glsl"

#include "glint_abi.glsl" // SOBOL_SALT, SOBOL_BLOCK_BITS, PAIRS_PER_BOUNCE, SAMPLER_*

// sobol_burley::parts::hash.
uint sobol_hash(uint n) {
    n ^= 0xe6fe3bebu;
    n ^= n >> 16u;
    n *= 0x7feb352du;
    n ^= n >> 15u;
    n *= 0x846ca68bu;
    n ^= n >> 16u;
    return n;
}

// sobol_burley::parts::owen_scramble_rev: a nested (Owen) scramble of a
// bit-reversed integer (each bit flips by the bits below it).
uint owen_scramble_rev(uint n_rev, uint scramble) {
    n_rev ^= n_rev * 0x3d20adeau;
    n_rev += scramble;
    n_rev *= (scramble >> 16u) | 1u;
    n_rev ^= n_rev * 0x05526c56u;
    n_rev ^= n_rev * 0x53a22864u;
    return n_rev;
}

// sobol_burley::parts::u32_to_f32_norm: the top 23 bits, exact.
float u32_to_f32_norm(uint n) {
    return uintBitsToFloat((n >> 9u) | 0x3f800000u) - 1.0;
}

uint pair_seed(uint key, uint pixel, uint sample_index, uint pair) {
    return pcg4d(uvec4(pixel, pair, sample_index >> SOBOL_BLOCK_BITS, key ^ SOBOL_SALT)).x;
}

// glint_cpu::sobol::sobol_dim1: Sobol dimension 1 of the index bits, the
// XOR of the taken direction numbers (Pascal's triangle mod 2) in four
// shift-and-XOR steps.
uint sobol_dim1(uint b) {
    uint v = b & 0xffffu;
    v ^= (v >> 1u) & 0x5555u;
    v ^= (v >> 2u) & 0x3333u;
    v ^= (v >> 4u) & 0x0f0fu;
    v ^= (v >> 8u) & 0x00ffu;
    return v;
}

// sobol_burley::sample(i, 0, seed) and sample(i, 1, seed) at once (they
// share the index shuffle).
vec2 sobol_2d(uint key, uint pixel, uint sample_index, uint pair) {
    uint seed = pair_seed(key, pixel, sample_index, pair);
    uint i = sample_index & ((1u << SOBOL_BLOCK_BITS) - 1u);
    uint idx = owen_scramble_rev(bitfieldReverse(i), sobol_hash(seed ^ 0x79c68e4au));
    // The top 16 bits: dimension 0 itself, dimension 1 through sobol_dim1.
    uint bits = bitfieldReverse(idx) & 0xffffu;
    uint s = seed * 0x9c8f2d3bu;
    uint x = owen_scramble_rev(bits, sobol_hash(s ^ 0x912f69bau));
    uint y = owen_scramble_rev(sobol_dim1(bits), sobol_hash(s ^ 0x174f18abu));
    return vec2(u32_to_f32_norm(bitfieldReverse(x)), u32_to_f32_norm(bitfieldReverse(y)));
}

float sobol_sample(uint key, uint pixel, uint sample_index, uint dim) {
    vec2 p = sobol_2d(key, pixel, sample_index, dim / 2u);
    return (dim & 1u) == 0u ? p.x : p.y;
}

// glint_cpu::sobol::PathSampler.
struct Sampler {
    uint kind;
    Rng rng;
    uint bounce;
};

struct BounceSamples {
    float light_cat;
    float light_idx;
    vec2 light;
    float bsdf_lobe;
    vec2 bsdf;
    float rr;
};

Sampler sampler_new(uint kind, uint key, uint pixel, uint sample_index) {
    Sampler s;
    s.kind = kind;
    s.rng = rng_new(key, pixel, sample_index);
    s.bounce = 0u;
    return s;
}

vec2 sampler_pixel_2d(inout Sampler s) {
    if (s.kind == SAMPLER_SOBOL) {
        return sobol_2d(s.rng.key, s.rng.pixel, s.rng.sample_index, 0u);
    }
    return rng_next_2d(s.rng);
}

BounceSamples sampler_bounce(inout Sampler s) {
    BounceSamples b;
    if (s.kind == SAMPLER_SOBOL) {
        uint p = 1u + PAIRS_PER_BOUNCE * s.bounce;
        s.bounce += 1u;
        b.light = sobol_2d(s.rng.key, s.rng.pixel, s.rng.sample_index, p);
        b.bsdf = sobol_2d(s.rng.key, s.rng.pixel, s.rng.sample_index, p + 1u);
        vec2 cat_idx = sobol_2d(s.rng.key, s.rng.pixel, s.rng.sample_index, p + 2u);
        vec2 lobe_rr = sobol_2d(s.rng.key, s.rng.pixel, s.rng.sample_index, p + 3u);
        b.light_cat = cat_idx.x;
        b.light_idx = cat_idx.y;
        b.bsdf_lobe = lobe_rr.x;
        b.rr = lobe_rr.y;
    } else {
        b.light_cat = rng_next_f32(s.rng);
        b.light_idx = rng_next_f32(s.rng);
        b.light = rng_next_2d(s.rng);
        b.bsdf_lobe = rng_next_f32(s.rng);
        b.bsdf = rng_next_2d(s.rng);
        b.rr = rng_next_f32(s.rng);
    }
    return b;
}

#endif
