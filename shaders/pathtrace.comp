#version 460
#ifdef GLINT_RAY_QUERY
// pathtrace_rq (--traversal hardware): ray_query.glsl in place of bvh.glsl.
#extension GL_EXT_ray_query : require
#endif
// The GPU path tracer as a compute kernel (pathtrace.glsl): one invocation
// per pixel, 8x8 workgroups.
layout(local_size_x = 8, local_size_y = 8) in;

#include "pathtrace.glsl"

void main() {
    render_pixel(gl_GlobalInvocationID.xy);
}
