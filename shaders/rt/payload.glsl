// What the ray tracing pipeline's stages hand back to ray generation
// (rt/trace.glsl): the closest hit of a ray (payload location 0, written
// by rt/closest_hit.rchit, or marked a miss by rt/miss.rmiss) and a
// shadow ray's verdict (location 1, cleared by rt/shadow_miss.rmiss).
#ifndef GLINT_RT_PAYLOAD_GLSL
#define GLINT_RT_PAYLOAD_GLSL

// `geometry` of a ray that hit nothing.
#define RT_MISS 0xffffffffu

struct RtHit {
    float t;
    // The acceleration structure's instance custom index, geometry and
    // primitive index (tri_map.glsl turns them into a triangles[] index).
    uint instance;
    uint geometry;
    uint primitive;
    // Barycentrics of p1 and p2, as Hit.u and Hit.v.
    float u;
    float v;
};

#define RT_HIT_PAYLOAD 0
#define RT_SHADOW_PAYLOAD 1

// Shader binding table: ray generation, the miss shaders in this order,
// one hit group (closest hit + any hit); src/gpu/rt_pipeline.rs lays it out.
#define RT_MISS_HIT 0u
#define RT_MISS_SHADOW 1u

#endif
