#version 100
// Terrain tile vertex shader, GLSL ES 1.00. No texture reads: positions and
// heights arrive as attributes from the tile's own block of the tile buffer,
// or from its cluster's block (Polok; src/tiles/block.rs, src/clusters/), the
// tile's placement as uniforms. Positions are relative to the camera, from
// integer post numbers counted from an anchor post next to it: a post two
// tiles share gets the same bits from both, so edges are watertight.
//
// The morph mirrors src/lod/morph.rs line for line: the factor grows from 0 at
// u_morph.x to 1 at u_morph.y with the vertex's distance to the camera,
// measured with its unmorphed height.

attribute vec4 a_grid;    // post i, post j (in the tile's posts), skirt edge 1..4 or 0, member slot
attribute vec2 a_height;  // this level's height, the parent level's height
attribute vec4 a_normal;  // normal xy at this level, at the parent level

uniform mat4 u_view_projection;
// Per member tile of the draw (a cluster's up to 16, or the one tile at
// slot 0), selected by the vertex's slot (a_grid.w):
// [2 slot]:     south-west post numbered from the anchor (xy), level-0 posts
//               per vertex post (z), skirt shares (w: bits 4(k-1) to 4k-1
//               for edge k, fifteenths of the skirt depth it hangs, 0 none);
// [2 slot + 1]: morph start, morph end, skirt depth (the deepest), unused.
uniform vec4 u_members[32];
uniform vec4 u_posts;     // level-0 post spacing (xy), camera minus anchor post (zw), metres
uniform vec4 u_frame;     // camera altitude, 1 / (2 R) or 0 for a flat earth, the data's last post numbered from the anchor (zw)

varying vec3 v_normal;
varying float v_relative_height;  // terrain height minus aircraft altitude
varying float v_height;
varying float v_distance;
varying vec3 v_position;     // camera-relative, for the accuracy tool's position output
varying float v_void;        // 1 at a post without data, 0 elsewhere (see VOIDS in the fragment shaders)
varying vec2 v_beyond;       // posts past the data's last post, east and north (clipped where above 0)

void main() {
    int slot = int(a_grid.w);
    vec4 tile = u_members[2 * slot];
    vec4 ranges = u_members[2 * slot + 1];
    vec2 post = tile.xy + a_grid.xy * tile.z;
    vec2 position = post * u_posts.xy - u_posts.zw;
    // Linear across every triangle, so the clip at 0 is the data's edge.
    v_beyond = post - u_frame.zw;
    float altitude = u_frame.x;
    // A post without data carries tiles::NO_DATA (-1e9 m) and, as its target,
    // a real height nearby: its triangles are dropped, but stay small.
    bool no_data = a_height.x < -1.0e8;
    float own = no_data ? a_height.y : a_height.x;
    v_void = no_data ? 1.0 : 0.0;
    float distance = length(vec3(position, own - altitude));
    float morph = clamp((distance - ranges.x) / (ranges.y - ranges.x), 0.0, 1.0);
    float height = mix(own, a_height.y, morph);
    float drop = dot(position, position) * u_frame.y;
    // Edge k hangs its skirt its share of the depth: 4-bit field k-1 of
    // tile.w (an integer below 2^16, exact in a highp float), fifteenths.
    float share = a_grid.z > 0.5 ? mod(floor(tile.w / exp2(4.0 * (a_grid.z - 1.0))), 16.0) : 0.0;
    float z = height - share / 15.0 * ranges.z - altitude - drop;
    vec2 n = mix(a_normal.xy, a_normal.zw, morph);
    v_normal = vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
    v_relative_height = height - altitude;
    v_height = height;
    v_distance = length(vec3(position, z));
    v_position = vec3(position, z);
    gl_Position = u_view_projection * vec4(position, z, 1.0);
}
