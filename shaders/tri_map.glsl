// The geometry layout of the acceleration structures (src/gpu/accel.rs),
// shared by both hardware traversals (ray_query.glsl, rt/). Each TLAS
// instance refers to a BLAS over a range of the triangles (by default one
// over all of them), and its custom index c says where they are: without
// alpha-tested materials the BLAS has one opaque geometry whose primitive
// i is triangles[c + i]. With them (RQ_MASKED != 0) geometry 0 holds the
// opaque triangles (flagged opaque: the traversal never stops for them)
// and geometry 1 the alpha-tested ones (non-opaque: an any-hit test runs
// BVH_PRESENT, the alpha test, on each); tri_map maps them back from c on:
// tri_map[c] is the opaque count n, then the opaque triangles' indices,
// then the alpha-tested ones'.
//
// The includer declares `uint tri_map[]` (bindings.glsl with
// GLINT_RAY_QUERY or GLINT_RAY_TRACING) and `#define RQ_MASKED
// <expression>`, nonzero when geometry 1 exists.
#ifndef GLINT_TRI_MAP_GLSL
#define GLINT_TRI_MAP_GLSL

// The triangles[] index of primitive `prim` of geometry `geom` of the
// instance whose custom index is `c`.
uint rq_triangle(uint c, uint geom, uint prim) {
    if (RQ_MASKED == 0u) {
        return c + prim;
    }
    return geom == 0u ? tri_map[c + 1u + prim] : tri_map[c + 1u + tri_map[c] + prim];
}

#endif
