// The alpha test of the hardware-traversal kernel tests (tests/gpu_ray_query.rs):
// every third triangle is "alpha-tested" and keeps only the hits with
// u + 0.5 v < 0.4; the others are opaque. Shared by bvh_mask_test.comp (the
// software traversal) and ray_query_test.comp, and mirrored by the Rust.
bool test_mask_masked(uint tri) {
    return tri % 3u == 0u;
}

bool test_mask(uint tri, float u, float v) {
    return !test_mask_masked(tri) || u + 0.5 * v < 0.4;
}
