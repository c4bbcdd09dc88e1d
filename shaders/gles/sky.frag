#version 100
// Sky gradient above the horizon and ground colour below it. The horizon is
// lowered by the dip of a spherical earth seen from the aircraft's altitude.
#ifdef GL_FRAGMENT_PRECISION_HIGH
precision highp float;
#else
precision mediump float;
#endif

uniform mat4 u_inverse_view_projection;
uniform vec4 u_horizon;    // sine of the horizon dip, unused x3
uniform vec3 u_zenith;
uniform vec3 u_haze;
uniform vec3 u_ground;
varying vec2 v_ndc;

void main() {
    vec4 far = u_inverse_view_projection * vec4(v_ndc, 1.0, 1.0);
    vec4 near = u_inverse_view_projection * vec4(v_ndc, -1.0, 1.0);
    vec3 direction = normalize(far.xyz / far.w - near.xyz / near.w);
    float elevation = direction.z + u_horizon.x;
    vec3 colour;
    if (elevation >= 0.0) {
        colour = mix(u_haze, u_zenith, clamp(elevation * 2.5, 0.0, 1.0));
    } else {
        colour = mix(u_haze, u_ground, clamp(-elevation * 6.0, 0.0, 1.0));
    }
    gl_FragColor = vec4(colour, 1.0);
}
