#version 100
// Full-screen triangle for the sky; the fragment shader turns each pixel
// into a view direction.
attribute vec2 a_corner;
varying vec2 v_ndc;

void main() {
    v_ndc = a_corner;
    gl_Position = vec4(a_corner, 0.999999, 1.0);
}
