#version 100
// Sky gradient above the horizon; below it, where no terrain is drawn over
// the sky, the "no data" pattern: grey diagonal hatching fixed to the screen,
// which no terrain colour, shading or haze can produce, so a pilot never
// takes missing data for low or distant terrain. The horizon is lowered by
// the dip of a spherical earth seen from the aircraft's altitude.
#ifdef GL_FRAGMENT_PRECISION_HIGH
precision highp float;
#else
precision mediump float;
#endif

uniform mat4 u_inverse_view_projection;
uniform vec4 u_horizon;    // sine of the horizon dip, unused x3
uniform vec3 u_zenith;
uniform vec3 u_haze;
uniform vec3 u_no_data;   // the hatching's dark colour; its stripes are twice as bright
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
        // Stripes 6 px wide every 16 px, at 45 degrees.
        float stripe = step(mod(gl_FragCoord.x + gl_FragCoord.y, 16.0), 6.0);
        colour = u_no_data * (1.0 + stripe);
    }
    gl_FragColor = vec4(colour, 1.0);
}
