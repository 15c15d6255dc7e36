// The path tracer: PathTracer::sample of cpu/src/integrator/mod.rs, step
// by step under the same names (read its header for the MIS, depth,
// Russian roulette, ray offset and light-leak rules). Binding table:
// bindings.glsl. render_pixel renders one pixel's samples
// [push.sample_start, push.sample_start + push.sample_count), adding each
// sample to the running sums in accum (glint_cpu::film::add_sample), in
// sample order, and the rays traced to ray_counts.
//
// One source, three kernels, which differ only in how a ray finds its hit
// (bvh_intersect, bvh_occluded):
//   - pathtrace.comp: glint's BVH, bvh.glsl (--traversal software);
//   - pathtrace.comp with GLINT_RAY_QUERY (pathtrace_rq): ray queries,
//     ray_query.glsl (--traversal hardware --ray-tracing query);
//   - rt/raygen.rgen (GLINT_RAY_TRACING): traceRayEXT in a ray tracing
//     pipeline, rt/trace.glsl (--traversal hardware --ray-tracing pipeline).
#ifndef GLINT_PATHTRACE_GLSL
#define GLINT_PATHTRACE_GLSL

#include "features.glsl"
#include "bindings.glsl"
#include "texture.glsl"
// The alpha-test hook (MASK, BLEND) at bvh.glsl's leaf triangle test, for
// the ray (o, d).
bool bvh_present(uint tri, float u, float v, vec3 o, vec3 d) {
    return !HAS(F_ALPHA_MASKS) || params.masked == 0u || alpha_pass(floatBitsToUint(triangles[tri].p0.w), tri, u, v, o, d);
}
#define BVH_PRESENT(tri, u, v, o, d) bvh_present(tri, u, v, o, d)
#if defined(GLINT_RAY_QUERY)
#define RQ_MASKED (HAS(F_ALPHA_MASKS) ? params.masked : 0u)
#include "ray_query.glsl"
#elif defined(GLINT_RAY_TRACING)
#define RQ_MASKED (HAS(F_ALPHA_MASKS) ? params.masked : 0u)
#include "rt/trace.glsl"
#else
#include "bvh.glsl"
#endif
#include "bsdf/bsdf.glsl"
#include "bsdf/fold.glsl"
#include "integrator/rng.glsl"
#include "integrator/sobol.glsl"
#include "integrator/frame.glsl"
#include "integrator/camera.glsl"
#include "integrator/envmap.glsl"
#include "integrator/lights.glsl"

// RR_DEPTH, RR_MAX_PROB, RAY_ERR_GAMMA (pbrt-v4's gamma(7)), SHADOW_EPS
// (its ShadowEpsilon) and RAY_ERR_TRI (the triangle test's relative
// margin): glint_abi.glsl, from glint_cpu::abi.

// Componentwise error bound of a point interpolated from the triangle,
// plus the triangle test's margin (hit_error in cpu/src/integrator).
vec3 hit_error(vec3 p0, vec3 p1, vec3 p2) {
    vec3 e = max(p0, max(p1, p2)) - min(p0, min(p1, p2));
    float extent = max(e.x, max(e.y, e.z));
    return RAY_ERR_GAMMA * max(abs(p0), max(abs(p1), abs(p2))) + vec3(RAY_ERR_TRI * extent);
}

// pbrt-v4's NextFloatUp / NextFloatDown, on the bits.
float next_float_up(float v) {
    if (isinf(v) && v > 0.0) {
        return v;
    }
    uint b = floatBitsToUint(v);
    if (b == 0x80000000u) {
        b = 0u;
    }
    b = v >= 0.0 ? b + 1u : b - 1u;
    return uintBitsToFloat(b);
}

float next_float_down(float v) {
    if (isinf(v) && v < 0.0) {
        return v;
    }
    uint b = floatBitsToUint(v);
    if (b == 0u) {
        b = 0x80000000u;
    }
    b = v > 0.0 ? b - 1u : b + 1u;
    return uintBitsToFloat(b);
}

// pbrt-v4's OffsetRayOrigin.
vec3 offset_origin(vec3 p, vec3 err, vec3 ng, vec3 w) {
    float d = dot(abs(ng), err);
    vec3 offset = ng * d;
    if (dot(w, ng) < 0.0) {
        offset = -offset;
    }
    vec3 po = p + offset;
    for (int i = 0; i < 3; i++) {
        if (offset[i] > 0.0) {
            po[i] = next_float_up(po[i]);
        } else if (offset[i] < 0.0) {
            po[i] = next_float_down(po[i]);
        }
    }
    return po;
}

float shadow_tmax(float len, vec3 q) {
    vec3 a = abs(q);
    return len * (1.0 - SHADOW_EPS) - 2.0 * RAY_ERR_GAMMA * max(a.x, max(a.y, a.z));
}

struct SurfaceFrame {
    vec3 ng;
    vec3 ns;
    Frame frame;
    // A normal-mapped hit on a BSDF without transmission: directions below
    // the geometric surface fold back above it (bsdf/fold.glsl).
    bool fold;
};

SurfaceFrame surface(uint tri, float u, float v) {
    Triangle t = triangles[tri];
    SurfaceFrame sf;
    sf.ng = normalize(triangle_normal(t));
    float w = 1.0 - u - v;
    sf.ns = sf.ng;
    sf.fold = false;
    // The triangle's packed shading data (glint_cpu::Scene::set_shading).
    uint flags = floatBitsToUint(t.p2.w);
    uint off = flags >> TRI_SHADING_SHIFT;
    if ((flags & TRI_NORMALS) != 0u) {
        vec3 n = w * shading[off].xyz + u * shading[off + 1u].xyz + v * shading[off + 2u].xyz;
        off += 3u;
        float len2 = dot(n, n);
        if (len2 > 0.0 && !isinf(len2)) {
            n = n / sqrt(len2);
            // On the geometric normal's side: the BSDF's +z is the outside.
            sf.ns = dot(n, sf.ng) < 0.0 ? -n : n;
        }
    }
    if ((flags & TRI_TANGENTS) != 0u) {
        sf.frame = frame_from_normal_tangent(sf.ns, w * shading[off].xyz + u * shading[off + 1u].xyz + v * shading[off + 2u].xyz);
    } else {
        sf.frame = frame_from_normal(sf.ns);
    }
    return sf;
}

// PathTracer::apply_textures: the normal map tilts the shading frame, the
// other textures set the material's parameters.
void apply_textures(uint material, uint tri, float u, float v, vec3 wo, inout SurfaceFrame sf, inout Material m) {
    MaterialTextures mt = material_textures[material];
    if (!material_textures_used(mt)) {
        return;
    }
    Frame unmapped = sf.frame;
    vec3 ns = normal_mapped(mt, tri, u, v, sf.ng, wo, sf.frame.s, sf.frame.t, sf.frame.n);
    if (ns != sf.ns) {
        sf.frame = frame_from_normal_tangent(ns, sf.frame.s);
        sf.ns = ns;
    }
    m = textured_bsdf(mt, m, tri, u, v);
    sf.fold = HAS(F_NORMAL_MAP) && mt.normal.texture != NO_TEXTURE && !bsdf_has_transmission(m);
    // The clear coat's own normal, where a normal map tilts either.
    if ((m.kind == KIND_COATED || m.kind == KIND_METALLIC) && m.extra.y > 0.0
        && (mt.normal.texture != NO_TEXTURE || mt.clearcoat_normal.texture != NO_TEXTURE)) {
        m.extra.w = clearcoat_normal_code(mt, tri, u, v, sf.ng, unmapped.s, unmapped.t, unmapped.n,
                                          sf.frame.s, sf.frame.t, sf.frame.n);
    }
}

// The shadow ray toward a light sample, from the offset origin to just
// short of the light point q (PathTracer::shadow_ray).
void shadow_ray(vec3 p, vec3 err, vec3 ng, LightSample ls, out vec3 o, out vec3 d, out float tmax) {
    o = offset_origin(p, err, ng, ls.wi);
    if (!ls.at_infinity) {
        vec3 q = p + ls.wi * ls.dist;
        vec3 to = q - o;
        float len = length(to);
        d = to / len;
        tmax = shadow_tmax(len, q);
    } else {
        d = ls.wi;
        tmax = GLINT_FLT_MAX;
    }
}

vec3 path_sample(uint x, uint y, uint s, inout uint rays) {
    uint pixel = y * params.width + x;
    Sampler rng = sampler_new(params.sampler_kind, params.seed_key, pixel, s);
    vec3 ray_o;
    vec3 ray_d;
    camera_ray(x, y, sampler_pixel_2d(rng), ray_o, ray_d);

    vec3 radiance = vec3(0.0);
    vec3 throughput = vec3(1.0);
    float eta = 1.0;
    uint depth = 0u;
    // An emitter the ray finds is MIS-weighted only when the previous
    // vertex sampled lights and its BSDF sample was not a delta.
    bool prev_mis = false;
    float prev_bsdf_pdf = 0.0;
    vec3 prev_bg_normal = vec3(0.0);
    vec3 prev_p = vec3(0.0); // the previous vertex, where light sampling started
    bool nee = params.nee != 0u;

    for (;;) {
        rays += 1u;
        Hit hit;
        if (!bvh_intersect(ray_o, ray_d, GLINT_FLT_MAX, hit)) {
            if (HAS(F_BACKGROUND) && params.p_background > 0.0) {
                float w = 1.0;
                if (prev_mis) {
                    float lp = lights_background_pdf(prev_bg_normal, ray_d);
                    w = mis_bsdf(params.mis, prev_bsdf_pdf, lp);
                }
                radiance += throughput * w * lights_background_radiance(ray_d);
            }
            break;
        }
        Triangle tri = triangles[hit.tri];
        // Beer-Lambert inside a solid dielectric (glint_cpu integrator's
        // `absorb`): reached from the back face, the segment ran inside;
        // a dielectric's k is its interior's sigma_a.
        if (HAS(F_DIELECTRIC) && dot(ray_d, triangle_normal(tri)) > 0.0) {
            uint mi = floatBitsToUint(tri.p0.w);
            if (materials[mi].kind == KIND_DIELECTRIC) {
                throughput *= exp(-materials[mi].k.xyz * hit.t);
            }
        }
        vec3 p = (1.0 - hit.u - hit.v) * tri.p0.xyz + hit.u * tri.p1.xyz + hit.v * tri.p2.xyz;
        vec3 p_err = hit_error(tri.p0.xyz, tri.p1.xyz, tri.p2.xyz);
        vec3 wo = -ray_d;

        vec3 le;
        if (HAS(F_AREA_LIGHTS) && floatBitsToUint(tri.p1.w) != NO_LIGHT && emitted(tri, hit.tri, hit.u, hit.v, wo, le)) {
            float w = 1.0;
            if (prev_mis) {
                float lp = lights_area_pdf(hit.tri, prev_p, ray_d, hit.t);
                w = mis_bsdf(params.mis, prev_bsdf_pdf, lp);
            }
            radiance += throughput * w * le;
        }

        // depth + 1 >= max_depth, saturating (max_depth 0xffffffff: never).
        if (!HAS(F_BOUNCES) || depth >= params.max_depth - 1u) {
            break;
        }

        BounceSamples u = sampler_bounce(rng);
        float u_light_cat = u.light_cat;
        float u_light_idx = u.light_idx;
        vec2 u_light = u.light;
        float u_bsdf_lobe = u.bsdf_lobe;
        vec2 u_bsdf = u.bsdf;
        float u_rr = u.rr;

        SurfaceFrame sf = surface(hit.tri, hit.u, hit.v);
        uint material = floatBitsToUint(tri.p0.w);
        Material m = materials[material];
        if (HAS(F_TEXTURES) && params.textured != 0u) {
            apply_textures(material, hit.tri, hit.u, hit.v, wo, sf, m);
        }
        vec3 wo_local = frame_to_local(sf.frame, wo);
        // A normal-mapped reflecting hit folds its BSDF (bsdf/fold.glsl).
        bool fold = HAS(F_NORMAL_MAP) && sf.fold;
        vec3 fold_n = fold ? fold_normal(frame_to_local(sf.frame, sf.ng), wo_local) : vec3(0.0);
        vec3 bg_normal = background_direction_frame(sf.ns, wo, bsdf_has_transmission(m));

        bool lights_present = params.p_area + params.p_punctual + params.p_background > 0.0;
        bool sample_lights = HAS(F_NEE) && nee && lights_present && !bsdf_is_delta(m);
        // The BSDF sample first (its random numbers are its own): folded,
        // its mirror image is evaluated in the light sample's loop below.
        BsdfSample bs;
        bool sampled = bsdf_sample(m, wo_local, u_bsdf_lobe, u_bsdf, bs);
        bool partner = fold && sampled && !bs.delta;

        // Next-event estimation: the light-leak rule, or folded
        // (Fold::eval_pdf) f |cos| and the density summed over wi and its
        // mirror image.
        LightSample ls;
        bool lit = sample_lights && lights_sample(p, bg_normal, u_light_cat, u_light_idx, u_light, ls);
        vec3 wi_local = lit ? frame_to_local(sf.frame, ls.wi) : vec3(0.0, 0.0, 1.0);
        bool valid = lit && (fold ? dot(wi_local, fold_n) > 0.0
                                  : (dot(ls.wi, sf.ng) > 0.0) == (wi_local.z > 0.0));
        uint terms = valid ? (fold ? 2u : 1u) : 0u;
        // One site evaluates them all, the light sample's terms and then
        // the BSDF sample's mirror image (lavapipe's compile time grows
        // with every inlined copy of the BSDFs); a kernel with normal maps
        // takes the densities here too, others only for a clear shadow ray.
        vec3 f = vec3(0.0);
        float pdf = 0.0;
        vec3 partner_f = vec3(0.0);
        float partner_pdf = 0.0;
        uint evals = terms + (partner ? 1u : 0u);
        for (uint k = 0u; k < evals; ++k) {
            vec3 w = k == terms ? fold_mirror(fold_n, bs.wi) : (k == 0u ? wi_local : fold_mirror(fold_n, wi_local));
            vec3 fk = bsdf_eval(m, wo_local, w) * abs(w.z);
            float pk = HAS(F_NORMAL_MAP) ? bsdf_pdf(m, wo_local, w) : 0.0;
            if (k < terms) {
                f += fk;
                pdf += pk;
            } else {
                partner_f = fk;
                partner_pdf = pk;
            }
        }
        if (valid && max(f.x, max(f.y, f.z)) > 0.0) {
            vec3 so;
            vec3 sd;
            float stmax;
            shadow_ray(p, p_err, sf.ng, ls, so, sd, stmax);
            rays += 1u;
            if (stmax > 0.0 && !bvh_occluded(so, sd, stmax)) {
                if (!HAS(F_NORMAL_MAP) && !ls.delta) {
                    pdf = bsdf_pdf(m, wo_local, wi_local);
                }
                float w = ls.delta ? 1.0 : mis_light(params.mis, ls.pdf, pdf);
                radiance += throughput * f * ls.weight * w;
            }
        }

        if (!sampled || (fold && !fold_reweigh(fold_n, partner_f, partner_pdf, bs))) {
            break;
        }
        vec3 wi = normalize(frame_to_world(sf.frame, bs.wi));
        // The light-leak rule; folded, wi is on wo's side of the surface
        // (up to rounding at the horizon).
        bool leaks = fold ? (dot(wi, sf.ng) > 0.0) != (dot(wo, sf.ng) > 0.0)
                          : (dot(wi, sf.ng) > 0.0) != (bs.wi.z > 0.0);
        if (leaks) {
            break;
        }
        throughput *= bs.weight;
        eta *= bs.eta;
        prev_mis = sample_lights && !bs.delta;
        prev_bsdf_pdf = bs.pdf;
        prev_bg_normal = bg_normal;
        prev_p = p;
        ray_o = offset_origin(p, p_err, sf.ng, wi);
        ray_d = wi;
        depth += 1u;

        if (depth >= RR_DEPTH) {
            float q = min(max(throughput.x, max(throughput.y, throughput.z)) * eta * eta, RR_MAX_PROB);
            if (!(u_rr < q)) {
                break;
            }
            throughput /= q;
        }
        if (!(max(throughput.x, max(throughput.y, throughput.z)) > 0.0)) {
            break;
        }
    }
    return radiance;
}

// One pixel's samples of this dispatch (or ray generation launch): px
// is gl_GlobalInvocationID.xy (pathtrace.comp) or gl_LaunchIDEXT.xy
// (rt/raygen.rgen); the grid may overhang the image.
void render_pixel(uvec2 px) {
    if (px.x >= params.width || px.y >= params.height) {
        return;
    }
    uint pixel = px.y * params.width + px.x;
    // An adaptive render's stopped pixel keeps its sums (binding 16).
    if (active_pixels[pixel] == 0u) {
        return;
    }
    uint rays = 0u;
    // Continue the running sums rather than adding a per-dispatch partial
    // sum: the additions then happen in sample order whatever the batch
    // sizes (which the host picks from timings), so an image does not
    // depend on them, and matches the CPU's sample-order sums.
    vec3 sum = accum[4u * pixel].xyz;
    vec3 sum_sq = accum[4u * pixel + 1u].xyz;
    vec3 run = accum[4u * pixel + 2u].xyz;
    vec3 sq = accum[4u * pixel + 3u].xyz;
    uint batch = max(params.variance_batch, 1u);
    for (uint s = push.sample_start; s < push.sample_start + push.sample_count; s++) {
        vec3 l = path_sample(px.x, px.y, s, rays);
        // A NaN or infinity would poison the pixel for good: drop it.
        if (any(isnan(l)) || any(isinf(l))) {
            l = vec3(0.0);
        }
        sum += l;
        sum_sq += l * l;
        run += l;
        if ((s + 1u) % batch == 0u) {
            sq += run * run;
            run = vec3(0.0);
        }
    }
    accum[4u * pixel] = vec4(sum, 0.0);
    accum[4u * pixel + 1u] = vec4(sum_sq, 0.0);
    accum[4u * pixel + 2u] = vec4(run, 0.0);
    accum[4u * pixel + 3u] = vec4(sq, 0.0);
    ray_counts[pixel] += rays;
}

#endif
