#version 100
// Smoke test: one flat colour from a uniform.
precision mediump float;

uniform vec4 u_colour;

void main() {
    gl_FragColor = u_colour;
}
