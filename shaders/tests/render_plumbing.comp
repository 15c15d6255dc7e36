#version 460
// Stand-in for pathtrace.comp with the same binding table and push
// constants, for testing the renderer's host side: each sample of pixel
// (x, y) with index s "measures" a value that depends on the pixel, the
// sample index and the first element of every scene buffer, so a test can
// predict the film exactly and catch a mix-up of bindings, batches or
// accumulation.
layout(local_size_x = 8, local_size_y = 8) in;

layout(std140, set = 0, binding = 0) uniform Params {
    vec4 pad[5];
    uint width;
    uint height;
    uint spp;
};
layout(std430, set = 0, binding = 1) readonly buffer Triangles { vec4 triangles[]; };
layout(std430, set = 0, binding = 2) readonly buffer Nodes { vec4 bvh_nodes[]; };
layout(std430, set = 0, binding = 3) readonly buffer Shading { vec4 shading[]; };
layout(std430, set = 0, binding = 4) readonly buffer Materials { vec4 materials[]; };
layout(std430, set = 0, binding = 5) readonly buffer Emitters { vec4 emitters[]; };
layout(std430, set = 0, binding = 6) readonly buffer Lights { vec4 lights[]; };
layout(std430, set = 0, binding = 7) buffer Accum { vec4 accum[]; };
layout(std430, set = 0, binding = 8) buffer RayCounts { uint ray_counts[]; };

layout(push_constant) uniform Push {
    uint sample_start;
    uint sample_count;
};

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= width || p.y >= height) {
        return;
    }
    uint pixel = p.y * width + p.x;
    vec3 base = vec3(float(p.x) + triangles[0].x + bvh_nodes[0].y,
                     float(p.y) + shading[0].z + materials[0].w,
                     emitters[0].x + lights[0].y);
    vec3 sum = vec3(0.0);
    vec3 sum_sq = vec3(0.0);
    // Variance batches of 4 samples, the running batch sum carried from
    // dispatch to dispatch in accum like pathtrace.comp's.
    vec3 run = accum[4 * pixel + 2].xyz;
    vec3 sq = vec3(0.0);
    for (uint s = sample_start; s < sample_start + sample_count; s++) {
        vec3 v = base + vec3(0.0, 0.0, float(s));
        sum += v;
        sum_sq += v * v;
        run += v;
        if ((s + 1u) % 4u == 0u) {
            sq += run * run;
            run = vec3(0.0);
        }
    }
    accum[4 * pixel] += vec4(sum, 0.0);
    accum[4 * pixel + 1] += vec4(sum_sq, 0.0);
    accum[4 * pixel + 2] = vec4(run, 0.0);
    accum[4 * pixel + 3] += vec4(sq, 0.0);
    ray_counts[pixel] += 3u * sample_count;
}
