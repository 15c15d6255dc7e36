// BVH traversal: the GLSL mirror of glint_cpu::bvh (cpu/src/bvh/traverse.rs
// and wide_traverse.rs), function for function under the same names, so a
// CPU/GPU difference can be pinned to one of them by a kernel test
// (shaders/tests/bvh_test.comp, bvh2_test.comp).
//
// bvh_intersect / bvh_occluded traverse the 4-wide BVH (glint_cpu::Bvh4,
// what renders use); with BVH_BINARY defined, the binary one (glint_cpu::Bvh,
// kept as the reference the wide one is measured and tested against).
//
// The including kernel must, BEFORE including this file, declare
//   - a buffer array `Bvh4Node bvh_nodes[]` (`BvhNode bvh_nodes[]` with
//     BVH_BINARY; include "bvh_types.glsl" first),
//   - a buffer array `Triangle triangles[]`, in the BVH's leaf order,
//   - `#define BVH_NODE_COUNT <expression>`: the number of nodes; 0 for an
//     empty scene (Vulkan buffers cannot be empty, so the array's length
//     cannot say so), and then every query misses.
//   - optionally `#define BVH_PRESENT(tri, u, v, o, d) <bool expression>`:
//     the alpha-test hook at the leaf triangle test, given the query's ray
//     (default: always true).
#ifndef GLINT_BVH_GLSL
#define GLINT_BVH_GLSL

#ifndef BVH_PRESENT
#define BVH_PRESENT(tri, u, v, o, d) true
#endif

#include "bvh_types.glsl"

// BVH_STACK_SIZE, BVH_SLAB_PAD and the BVH4_* constants: glint_abi.glsl
// (via bvh_types.glsl).

// Per-ray constants of the slab and watertight triangle tests.
struct PreparedRay {
    vec3 o;
    vec3 d;
    // 1 / d with zero (and tiny) components replaced by +-1e30, so the slab
    // test never forms 0 * inf = NaN (tinybvh's safercp); exactly zero
    // components are then settled by zero_d in intersect_aabb.
    vec3 inv_d;
    // Which components of d are exactly zero (either sign).
    bvec3 zero_d;
    // Woop et al. 2013: kz is the dominant axis of d, kx and ky follow it
    // cyclically, swapped when d[kz] < 0 to keep the winding.
    int kx;
    int ky;
    int kz;
    // (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz]).
    vec3 shear;
};

float safe_rcp(float x) {
    if (abs(x) >= 1e-30) {
        return 1.0 / x;
    }
    // copysign(1e30, x), -0 included.
    return uintBitsToFloat(floatBitsToUint(1e30) | (floatBitsToUint(x) & 0x80000000u));
}

PreparedRay prepare_ray(vec3 o, vec3 d) {
    PreparedRay r;
    r.o = o;
    r.d = d;
    r.inv_d = vec3(safe_rcp(d.x), safe_rcp(d.y), safe_rcp(d.z));
    r.zero_d = equal(d, vec3(0.0));
    vec3 a = abs(d);
    int kz = (a.x >= a.y && a.x >= a.z) ? 0 : (a.y >= a.z ? 1 : 2);
    int kx = (kz + 1) % 3;
    int ky = (kx + 1) % 3;
    if (d[kz] < 0.0) {
        int tmp = kx;
        kx = ky;
        ky = tmp;
    }
    r.kx = kx;
    r.ky = ky;
    r.kz = kz;
    r.shear = vec3(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    return r;
}

// Entry distance of the ray into the box, clamped to >= 0, or BVH_INF when
// it misses the box within [0, tmax]. The pad widens both the far slab
// distance and tmax (the best hit so far): box and triangle distances round
// independently, and too wide only costs a triangle test.
float intersect_aabb(PreparedRay r, vec3 bmin, vec3 bmax, float tmax) {
    vec3 t1 = (bmin - r.o) * r.inv_d;
    vec3 t2 = (bmax - r.o) * r.inv_d;
    // Along an axis where d is exactly zero the slab holds the whole line when
    // the origin is within it, faces included, and none of it otherwise (the
    // 1e30 inverse would end the slab at t = 0 with the origin on a face).
    vec3 tlo = min(t1, t2);
    vec3 thi = max(t1, t2);
    if (any(r.zero_d)) {
        bvec3 ge = greaterThanEqual(r.o, bmin);
        bvec3 le = lessThanEqual(r.o, bmax);
        bvec3 inside = bvec3(ge.x && le.x, ge.y && le.y, ge.z && le.z);
        tlo = mix(tlo, mix(vec3(BVH_INF), vec3(-BVH_INF), inside), r.zero_d);
        thi = mix(thi, mix(vec3(-BVH_INF), vec3(BVH_INF), inside), r.zero_d);
    }
    float tnear = max(max(max(tlo.x, tlo.y), tlo.z), 0.0);
    float tfar = min(min(min(thi.x, thi.y), thi.z), tmax) * BVH_SLAB_PAD;
    return tnear <= tfar ? tnear : BVH_INF;
}

// Dekker's exact product (Veltkamp's split, no FMA: lavapipe's fma() did not
// match the CPU's fused one): p = fl(a b) and its rounding error e, p + e = a b exactly; then
// a b - c d from two of them, for the edge functions that round to exactly
// 0 (glint_cpu::bvh::traverse::difference_of_products, bit for bit).
vec2 two_product(float a, float b) {
    precise float p = a * b;
    precise float ta = VELTKAMP_SPLIT * a;
    precise float ah = ta - (ta - a);
    precise float al = a - ah;
    precise float tb = VELTKAMP_SPLIT * b;
    precise float bh = tb - (tb - b);
    precise float bl = b - bh;
    precise float e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    return vec2(p, e);
}

float difference_of_products(float a, float b, float c, float d) {
    precise vec2 x = two_product(a, b);
    precise vec2 y = two_product(c, d);
    precise float r = (x.x - y.x) + (x.y - y.y);
    return r;
}

// pbrt-v4's conservative bound on the triangle test's t error (deltaT),
// traverse.rs's t_error: the same operations in the same order.
float t_error(vec3 x, vec3 y, vec3 z, vec3 e, float det) {
    precise float max_x = max(max(abs(x.x), abs(x.y)), abs(x.z));
    precise float max_y = max(max(abs(y.x), abs(y.y)), abs(y.z));
    precise float max_z = max(max(abs(z.x), abs(z.y)), abs(z.z));
    precise float max_e = max(max(abs(e.x), abs(e.y)), abs(e.z));
    precise float delta_x = TRI_GAMMA5 * (max_x + max_z);
    precise float delta_y = TRI_GAMMA5 * (max_y + max_z);
    precise float delta_e = 2.0 * (TRI_GAMMA2 * max_x * max_y + delta_y * max_x + delta_x * max_y);
    precise float sum = TRI_GAMMA3 * max_e * max_z + delta_e * max_z + delta_x * max_e;
    return 3.0 * sum / abs(det);
}

// Watertight ray/triangle intersection (Woop, Benthin, Wald 2013, JCGT 2(1)).
// A hit with 0 < t < tmax writes t and the barycentrics u, v; both faces hit.
// `precise` forbids FMA contraction: the two triangles sharing an edge must
// compute exactly negated edge functions from bit-identical sheared vertices,
// which is what makes the test watertight.
bool intersect_triangle(PreparedRay r, Triangle tri, float tmax, out float t, out float u,
                        out float v) {
    t = 0.0;
    u = 0.0;
    v = 0.0;
    precise vec3 a = tri.p0.xyz - r.o;
    precise vec3 b = tri.p1.xyz - r.o;
    precise vec3 c = tri.p2.xyz - r.o;
    precise float ax = a[r.kx] - r.shear.x * a[r.kz];
    precise float ay = a[r.ky] - r.shear.y * a[r.kz];
    precise float bx = b[r.kx] - r.shear.x * b[r.kz];
    precise float by = b[r.ky] - r.shear.y * b[r.kz];
    precise float cx = c[r.kx] - r.shear.x * c[r.kz];
    precise float cy = c[r.ky] - r.shear.y * c[r.kz];
    // Scaled barycentrics: the 2D edge functions opposite A, B and C.
    precise float eu = cx * by - cy * bx;
    precise float ev = ax * cy - ay * cx;
    precise float ew = bx * ay - by * ax;
    // An edge function that rounds to exactly 0 is recomputed (traverse.rs
    // says why): a degenerate triangle then reports no false hit, and a
    // shared edge stays exactly negated (both triangles see the zero).
    if (eu == 0.0 || ev == 0.0 || ew == 0.0) {
        if (eu == 0.0) {
            eu = difference_of_products(cx, by, cy, bx);
        }
        if (ev == 0.0) {
            ev = difference_of_products(ax, cy, ay, cx);
        }
        if (ew == 0.0) {
            ew = difference_of_products(bx, ay, by, ax);
        }
    }
    if ((eu < 0.0 || ev < 0.0 || ew < 0.0) && (eu > 0.0 || ev > 0.0 || ew > 0.0)) {
        return false;
    }
    precise float det = eu + ev + ew;
    if (det == 0.0) {
        return false;
    }
    precise float az = r.shear.z * a[r.kz];
    precise float bz = r.shear.z * b[r.kz];
    precise float cz = r.shear.z * c[r.kz];
    precise float tt = (eu * az + ev * bz + ew * cz) / det;
    // Also rejects NaN; a hit within t's own error bound is not reported.
    if (!(tt > 0.0 && tt < tmax)) {
        return false;
    }
    if (!(tt > t_error(vec3(ax, bx, cx), vec3(ay, by, cy), vec3(az, bz, cz), vec3(eu, ev, ew), det))) {
        return false;
    }
    t = tt;
    u = ev / det;
    v = ew / det;
    return true;
}

#ifdef BVH_BINARY

// The binary BVH (cpu/src/bvh/traverse.rs).

// Closest hit in (0, tmax): front-to-back, nearer child first and the other
// pushed, the interval shrinking to the best hit so far.
bool bvh_intersect(vec3 o, vec3 d, float tmax, out Hit hit) {
    hit = Hit(tmax, BVH_NO_HIT, 0.0, 0.0);
    if (uint(BVH_NODE_COUNT) == 0u) {
        return false;
    }
    PreparedRay r = prepare_ray(o, d);
    if (intersect_aabb(r, bvh_nodes[0].min_left.xyz, bvh_nodes[0].max_count.xyz, tmax) == BVH_INF) {
        return false;
    }
    uint stack[BVH_STACK_SIZE];
    uint sp = 0u;
    uint node = 0u;
    while (true) {
        uint first = floatBitsToUint(bvh_nodes[node].min_left.w);
        uint count = floatBitsToUint(bvh_nodes[node].max_count.w);
        if (count > 0u) {
            for (uint i = first; i < first + count; i++) {
                float t, u, v;
                if (intersect_triangle(r, triangles[i], hit.t, t, u, v) && BVH_PRESENT(i, u, v, o, d)) {
                    hit = Hit(t, i, u, v);
                }
            }
        } else {
            uint c1 = first;
            uint c2 = first + 1u;
            float d1 = intersect_aabb(r, bvh_nodes[c1].min_left.xyz, bvh_nodes[c1].max_count.xyz, hit.t);
            float d2 = intersect_aabb(r, bvh_nodes[c2].min_left.xyz, bvh_nodes[c2].max_count.xyz, hit.t);
            if (d1 > d2) {
                float td = d1;
                d1 = d2;
                d2 = td;
                uint tc = c1;
                c1 = c2;
                c2 = tc;
            }
            if (d1 != BVH_INF) {
                if (d2 != BVH_INF) {
                    stack[sp] = c2;
                    sp++;
                }
                node = c1;
                continue;
            }
        }
        if (sp == 0u) {
            break;
        }
        sp--;
        node = stack[sp];
    }
    return hit.tri != BVH_NO_HIT;
}

// Any hit in (0, tmax): the first triangle hit ends the search. Children are
// still visited nearer first (tinybvh's IsOccluded): the near side is the
// likelier to hold a blocker.
bool bvh_occluded(vec3 o, vec3 d, float tmax) {
    if (uint(BVH_NODE_COUNT) == 0u) {
        return false;
    }
    PreparedRay r = prepare_ray(o, d);
    if (intersect_aabb(r, bvh_nodes[0].min_left.xyz, bvh_nodes[0].max_count.xyz, tmax) == BVH_INF) {
        return false;
    }
    uint stack[BVH_STACK_SIZE];
    uint sp = 0u;
    uint node = 0u;
    while (true) {
        uint first = floatBitsToUint(bvh_nodes[node].min_left.w);
        uint count = floatBitsToUint(bvh_nodes[node].max_count.w);
        if (count > 0u) {
            for (uint i = first; i < first + count; i++) {
                float t, u, v;
                if (intersect_triangle(r, triangles[i], tmax, t, u, v) && BVH_PRESENT(i, u, v, o, d)) {
                    return true;
                }
            }
        } else {
            uint c1 = first;
            uint c2 = first + 1u;
            float d1 = intersect_aabb(r, bvh_nodes[c1].min_left.xyz, bvh_nodes[c1].max_count.xyz, tmax);
            float d2 = intersect_aabb(r, bvh_nodes[c2].min_left.xyz, bvh_nodes[c2].max_count.xyz, tmax);
            if (d1 > d2) {
                float td = d1;
                d1 = d2;
                d2 = td;
                uint tc = c1;
                c1 = c2;
                c2 = tc;
            }
            if (d1 != BVH_INF) {
                if (d2 != BVH_INF) {
                    stack[sp] = c2;
                    sp++;
                }
                node = c1;
                continue;
            }
        }
        if (sp == 0u) {
            return false;
        }
        sp--;
        node = stack[sp];
    }
    return false;
}

#else

// The 4-wide BVH (cpu/src/bvh/wide_traverse.rs).


// intersect_aabb for the four child boxes at once, lane i computing exactly
// what intersect_aabb computes for slot i's box: the entry distance, or
// BVH_INF for a missed box or an empty slot.
vec4 intersect_aabb4(PreparedRay r, Bvh4Node n, float tmax) {
    vec4 t1x = (n.lo_x - r.o.x) * r.inv_d.x;
    vec4 t2x = (n.hi_x - r.o.x) * r.inv_d.x;
    vec4 t1y = (n.lo_y - r.o.y) * r.inv_d.y;
    vec4 t2y = (n.hi_y - r.o.y) * r.inv_d.y;
    vec4 t1z = (n.lo_z - r.o.z) * r.inv_d.z;
    vec4 t2z = (n.hi_z - r.o.z) * r.inv_d.z;
    vec4 tlox = min(t1x, t2x), thix = max(t1x, t2x);
    vec4 tloy = min(t1y, t2y), thiy = max(t1y, t2y);
    vec4 tloz = min(t1z, t2z), thiz = max(t1z, t2z);
    // 1 in a lane whose box misses because the origin lies outside the slab
    // of an axis along which d is exactly zero (see intersect_aabb); such an
    // axis then bounds nothing.
    uvec4 outside = uvec4(0u);
    if (any(r.zero_d)) {
        if (r.zero_d.x) {
            outside |= uvec4(lessThan(vec4(r.o.x), n.lo_x)) | uvec4(greaterThan(vec4(r.o.x), n.hi_x));
            tlox = vec4(-BVH_INF);
            thix = vec4(BVH_INF);
        }
        if (r.zero_d.y) {
            outside |= uvec4(lessThan(vec4(r.o.y), n.lo_y)) | uvec4(greaterThan(vec4(r.o.y), n.hi_y));
            tloy = vec4(-BVH_INF);
            thiy = vec4(BVH_INF);
        }
        if (r.zero_d.z) {
            outside |= uvec4(lessThan(vec4(r.o.z), n.lo_z)) | uvec4(greaterThan(vec4(r.o.z), n.hi_z));
            tloz = vec4(-BVH_INF);
            thiz = vec4(BVH_INF);
        }
    }
    vec4 tnear = max(max(max(tlox, tloy), tloz), vec4(0.0));
    vec4 tfar = min(min(min(thix, thiy), thiz), vec4(tmax)) * BVH_SLAB_PAD;
    uvec4 hit = uvec4(lessThanEqual(tnear, tfar)) & uvec4(lessThan(tnear, vec4(BVH_INF))) &
                uvec4(notEqual(n.child, uvec4(BVH4_SLOT_EMPTY))) & (uvec4(1u) - outside);
    return mix(vec4(BVH_INF), tnear, bvec4(hit));
}

// One compare-exchange of sort4's network, on (distance, slot).
#define BVH4_CX(a, b)                                         \
    if (k.b < k.a || (k.b == k.a && o.b < o.a)) {             \
        float tk = k.a;                                       \
        k.a = k.b;                                            \
        k.b = tk;                                             \
        uint to = o.a;                                        \
        o.a = o.b;                                            \
        o.b = to;                                             \
    }

// The slots in order of (distance, slot): misses (BVH_INF) last, ties to the
// lower slot; the same five compare-exchanges as the Rust.
uvec4 sort4(vec4 dist) {
    vec4 k = dist;
    uvec4 o = uvec4(0u, 1u, 2u, 3u);
    BVH4_CX(x, y)
    BVH4_CX(z, w)
    BVH4_CX(x, z)
    BVH4_CX(y, w)
    BVH4_CX(y, z)
    return o;
}

// Closest hit in (0, tmax): children nearest first, the others on the stack
// with their entry distance, dropped when popped if the best hit has moved in
// front of them (the box test's own criterion).
bool bvh_intersect(vec3 o, vec3 d, float tmax, out Hit hit) {
    hit = Hit(tmax, BVH_NO_HIT, 0.0, 0.0);
    if (uint(BVH_NODE_COUNT) == 0u) {
        return false;
    }
    PreparedRay r = prepare_ray(o, d);
    uint stack_ref[BVH4_STACK_SIZE];
    float stack_t[BVH4_STACK_SIZE];
    uint sp = 0u;
    uint cur = 0u;
    while (true) {
        if ((cur & BVH4_LEAF_BIT) != 0u) {
            uint first = cur & BVH4_LEAF_FIRST_MASK;
            uint count = ((cur >> 27) & 0xfu) + 1u;
            for (uint i = first; i < first + count; i++) {
                float t, u, v;
                if (intersect_triangle(r, triangles[i], hit.t, t, u, v) && BVH_PRESENT(i, u, v, o, d)) {
                    hit = Hit(t, i, u, v);
                }
            }
        } else {
            Bvh4Node n = bvh_nodes[cur];
            vec4 dist = intersect_aabb4(r, n, hit.t);
            uvec4 hits = uvec4(lessThan(dist, vec4(BVH_INF)));
            uint count = hits.x + hits.y + hits.z + hits.w;
            if (count > 0u) {
                uvec4 order = sort4(dist);
                for (uint k = count - 1u; k >= 1u; k--) {
                    stack_ref[sp] = n.child[order[k]];
                    stack_t[sp] = dist[order[k]];
                    sp++;
                }
                cur = n.child[order.x];
                continue;
            }
        }
        bool next = false;
        while (sp > 0u) {
            sp--;
            if (stack_t[sp] <= hit.t * BVH_SLAB_PAD) {
                cur = stack_ref[sp];
                next = true;
                break;
            }
        }
        if (!next) {
            break;
        }
    }
    return hit.tri != BVH_NO_HIT;
}

// Any hit in (0, tmax): the first triangle hit ends the search; children
// still nearest first.
bool bvh_occluded(vec3 o, vec3 d, float tmax) {
    if (uint(BVH_NODE_COUNT) == 0u) {
        return false;
    }
    PreparedRay r = prepare_ray(o, d);
    uint stack_ref[BVH4_STACK_SIZE];
    uint sp = 0u;
    uint cur = 0u;
    while (true) {
        if ((cur & BVH4_LEAF_BIT) != 0u) {
            uint first = cur & BVH4_LEAF_FIRST_MASK;
            uint count = ((cur >> 27) & 0xfu) + 1u;
            for (uint i = first; i < first + count; i++) {
                float t, u, v;
                if (intersect_triangle(r, triangles[i], tmax, t, u, v) && BVH_PRESENT(i, u, v, o, d)) {
                    return true;
                }
            }
        } else {
            Bvh4Node n = bvh_nodes[cur];
            vec4 dist = intersect_aabb4(r, n, tmax);
            uvec4 hits = uvec4(lessThan(dist, vec4(BVH_INF)));
            uint count = hits.x + hits.y + hits.z + hits.w;
            if (count > 0u) {
                uvec4 order = sort4(dist);
                for (uint k = count - 1u; k >= 1u; k--) {
                    stack_ref[sp] = n.child[order[k]];
                    sp++;
                }
                cur = n.child[order.x];
                continue;
            }
        }
        if (sp == 0u) {
            return false;
        }
        sp--;
        cur = stack_ref[sp];
    }
    return false;
}

#endif

#endif
