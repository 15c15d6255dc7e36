// Primary rays, twin of PinholeCamera::ray (cpu/src/camera.rs): box filter
// one pixel wide, `u` the offset within the pixel. Needs bindings.glsl.
#ifndef GLINT_INTEGRATOR_CAMERA_GLSL
#define GLINT_INTEGRATOR_CAMERA_GLSL

void camera_ray(uint x, uint y, vec2 u, out vec3 o, out vec3 d) {
    float sx = 2.0 * (float(x) + u.x) / float(params.width) - 1.0;
    float sy = 1.0 - 2.0 * (float(y) + u.y) / float(params.height);
    o = params.cam_origin.xyz;
    d = normalize(params.cam_forward.xyz + params.cam_right.xyz * sx + params.cam_up.xyz * sy);
}

#endif
