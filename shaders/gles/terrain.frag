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

varying vec3 v_normal;
varying float v_relative_height;
varying float v_height;
varying float v_distance;

// Hypsometric tint: lowland green through tan and brown to grey rock.
vec3 elevation_tint(float h) {
    vec3 low = vec3(0.30, 0.47, 0.25);
    vec3 mid = vec3(0.66, 0.60, 0.38);
    vec3 high = vec3(0.52, 0.40, 0.29);
    vec3 peak = vec3(0.80, 0.79, 0.77);
    float t = clamp(h / 1500.0, 0.0, 1.0);
    vec3 c = mix(low, mid, t);
    c = mix(c, high, clamp((h - 1500.0) / 1500.0, 0.0, 1.0));
    return mix(c, peak, clamp((h - 3000.0) / 2500.0, 0.0, 1.0));
}

void main() {
    vec3 n = normalize(v_normal);
    float light = 0.42 + 0.58 * max(dot(n, u_sun), 0.0);
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
