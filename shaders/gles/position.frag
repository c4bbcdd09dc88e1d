#version 100
// Position output for the accuracy tool: the surface point each pixel shows,
// relative to the camera in metres (x east, y north, z up, the curvature drop
// included), into an RGBA32F target. Alpha 1 marks terrain; the target is
// cleared to alpha 0, so sky reads as 0.
#ifdef GL_FRAGMENT_PRECISION_HIGH
precision highp float;
#else
precision mediump float;
#endif

varying vec3 v_position;
varying float v_curtain;  // above 0 on a curtain: no terrain, but it hides what lies behind

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
    gl_FragColor = v_curtain > 0.0 ? vec4(0.0) : vec4(v_position, 1.0);
}
