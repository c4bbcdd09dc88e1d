#version 100
// Flat colour: symbols are opaque, drawn over everything.
#ifdef GL_FRAGMENT_PRECISION_HIGH
precision highp float;
#else
precision mediump float;
#endif

varying vec4 v_colour;

void main() {
    gl_FragColor = v_colour;
}
