#version 100
// Terrain colour: elevation tint, slope shading, terrain-awareness bands
// relative to the aircraft, and haze toward the horizon colour.
#ifdef GL_FRAGMENT_PRECISION_HIGH
precision highp float;
#else
precision mediump float;
#endif

uniform vec3 u_sun;        // unit vector toward the sun
uniform vec4 u_awareness;  // warning above (m), caution below (m), haze distance (m), unused
uniform vec3 u_haze;       // horizon colour
uniform vec3 u_no_data;    // the "no data" hatching's dark colour, as the sky pass's

varying vec3 v_normal;
varying float v_relative_height;
varying float v_height;
varying float v_distance;
varying float v_curtain;

// Hypsometric tint in absolute metres, the bands charts use: lowland green,
// yellow-green hills, tan and brown mountains, grey rock, snow.
vec3 elevation_tint(float h) {
    vec3 c = vec3(0.24, 0.44, 0.22);
    c = mix(c, vec3(0.55, 0.60, 0.32), clamp(h / 800.0, 0.0, 1.0));
    c = mix(c, vec3(0.72, 0.62, 0.40), clamp((h - 800.0) / 800.0, 0.0, 1.0));
    c = mix(c, vec3(0.56, 0.41, 0.28), clamp((h - 1600.0) / 900.0, 0.0, 1.0));
    c = mix(c, vec3(0.58, 0.56, 0.54), clamp((h - 2500.0) / 900.0, 0.0, 1.0));
    return mix(c, vec3(0.93, 0.94, 0.96), clamp((h - 3600.0) / 1200.0, 0.0, 1.0));
}

#ifdef NO_DATA
// Drawn for tiles with posts without data: a triangle touching one is
// dropped whole (v_no_data is above 0 everywhere inside it). Also for tiles
// reaching past the data's last post: they are clipped there.
varying float v_no_data;
varying vec2 v_beyond;
#endif

void main() {
#ifdef NO_DATA
    if (v_no_data > 0.0 || max(v_beyond.x, v_beyond.y) > 0.0) {
        discard;
    }
#endif
    if (v_curtain > 0.0) {
        // The data's cut face: missing data, drawn as the sky pass draws it.
        float stripe = step(mod(gl_FragCoord.x + gl_FragCoord.y, 16.0), 6.0);
        gl_FragColor = vec4(u_no_data * (1.0 + stripe), 1.0);
        return;
    }
    vec3 n = normalize(v_normal);
    // Lambert from the sun plus a sky fill, so slopes facing away stay readable.
    float light = 0.30 + 0.75 * max(dot(n, u_sun), 0.0);
    vec3 colour = elevation_tint(v_height);
    if (v_relative_height >= u_awareness.x) {
        colour = vec3(0.85, 0.12, 0.10);
    } else if (v_relative_height >= -u_awareness.y) {
        colour = vec3(0.95, 0.68, 0.10);
    }
    colour *= light;
    float haze = clamp(v_distance / u_awareness.z, 0.0, 1.0);
    colour = mix(colour, u_haze, haze * haze);
    gl_FragColor = vec4(colour, 1.0);
}
