// The environment light: the GLSL mirror of glint_cpu::envmap (read its
// header for the mapping and the distribution). Needs bindings.glsl's
// env_texels[] and env_dist[] (marginal CDF and pmf over rows, then per row
// the CDF and pmf over its texels) and params.env_*.
#ifndef GLINT_ENVMAP_GLSL
#define GLINT_ENVMAP_GLSL

#define ENV_PI 3.14159265358979323846

uint env_sample_cdf(uint base, uint n, float u) {
    uint lo = 0u;
    uint hi = n > 0u ? n - 1u : 0u;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        if (u < env_dist[base + mid]) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

vec3 env_to_map(vec3 d) {
    float s = params.env_rot_sin;
    float c = params.env_rot_cos;
    return vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

vec3 env_to_world(vec3 d) {
    float s = params.env_rot_sin;
    float c = params.env_rot_cos;
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

vec2 env_direction_to_uv(vec3 d) {
    vec3 m = env_to_map(d);
    float theta = acos(clamp(m.y, -1.0, 1.0));
    float phi = atan(m.x, -m.z);
    if (phi < 0.0) {
        phi += 2.0 * ENV_PI;
    }
    return vec2(phi / (2.0 * ENV_PI), theta / ENV_PI);
}

vec3 env_uv_to_direction(vec2 uv) {
    float theta = uv.y * ENV_PI;
    float phi = uv.x * 2.0 * ENV_PI;
    float st = sin(theta);
    return env_to_world(vec3(st * sin(phi), cos(theta), -st * cos(phi)));
}

uvec2 env_texel_of(vec2 uv) {
    uint x = min(uint(uv.x * float(params.env_width)), params.env_width - 1u);
    uint y = min(uint(uv.y * float(params.env_height)), params.env_height - 1u);
    return uvec2(x, y);
}

vec3 env_radiance(vec3 d) {
    uvec2 t = env_texel_of(env_direction_to_uv(d));
    return env_texels[t.y * params.env_width + t.x].xyz;
}

float env_texel_pmf(uint x, uint y) {
    uint w = params.env_width;
    uint h = params.env_height;
    return env_dist[h + y] * env_dist[2u * h + 2u * w * y + w + x];
}

float env_pdf(vec3 d) {
    vec2 uv = env_direction_to_uv(d);
    float sin_t = sin(uv.y * ENV_PI);
    if (!(sin_t > 0.0)) {
        return 0.0;
    }
    uvec2 t = env_texel_of(uv);
    return env_texel_pmf(t.x, t.y) * float(params.env_width * params.env_height)
        / (2.0 * ENV_PI * ENV_PI * sin_t);
}

bool env_sample(vec2 u, out vec3 wi, out float pdf, out vec3 radiance) {
    uint w = params.env_width;
    uint h = params.env_height;
    uint y = env_sample_cdf(0u, h, u.y);
    float py = env_dist[h + y];
    float cy = y > 0u ? env_dist[y - 1u] : 0.0;
    float fy = clamp((u.y - cy) / py, 0.0, 1.0);
    uint row = 2u * h + 2u * w * y;
    uint x = env_sample_cdf(row, w, u.x);
    float px = env_dist[row + w + x];
    float cx = x > 0u ? env_dist[row + x - 1u] : 0.0;
    float fx = clamp((u.x - cx) / px, 0.0, 1.0);
    vec2 uv = vec2((float(x) + fx) / float(w), (float(y) + fy) / float(h));
    wi = env_uv_to_direction(uv);
    float sin_t = sin(uv.y * ENV_PI);
    pdf = px * py * float(w * h) / (2.0 * ENV_PI * ENV_PI * sin_t);
    radiance = env_texels[y * w + x].xyz;
    return pdf > 0.0 && !isinf(pdf);
}

#endif
