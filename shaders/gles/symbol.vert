#version 100
// Reference symbols and the failure flag: positions in pixels from the
// top-left corner (y down), turned into clip space; colours per vertex.
attribute vec2 a_position;
attribute vec4 a_colour;
uniform vec4 u_viewport;   // width, height (pixels), unused x2
varying vec4 v_colour;

void main() {
    vec2 ndc = vec2(2.0 * a_position.x / u_viewport.x - 1.0, 1.0 - 2.0 * a_position.y / u_viewport.y);
    v_colour = a_colour;
    gl_Position = vec4(ndc, 0.0, 1.0);
}
