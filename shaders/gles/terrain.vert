#version 100
// Terrain tile vertex shader, GLSL ES 1.00. No texture reads: positions and
// heights arrive as attributes from the tile's own block of the tile buffer,
// or from its cluster's block (Polok; src/tiles/block.rs, src/clusters/), the
// tile's placement as uniforms. Positions are relative to the camera, from
// integer post numbers counted from an anchor post next to it: a post two
// tiles share gets the same bits from both, so edges are watertight.
//
// Two frames (u_earth[0].w): the planar chart (metres east and north,
// lowered by d^2 / 2R), or the WGS 84 ellipsoid in the camera's own
// east-north-up axes (src/earth/frame.rs, whose NodePlace::local and
// to_camera this mirrors line for line): each vertex's latitude and
// longitude about its node's centre, its offset from the centre's surface
// point written with small terms only, rotated into the camera's axes and
// added to the centre's camera-relative position. Height, morph and skirts
// move along the vertex's geodetic up. A projected grid's latitude and
// longitude differences come from its node's series (src/earth/expansion.rs).
//
// The morph mirrors src/lod/morph.rs line for line: the factor grows from 0 at
// u_morph.x to 1 at u_morph.y with the vertex's distance to the camera,
// measured with its unmorphed height.

attribute vec4 a_grid;    // post i, post j (in the tile's posts), skirt edge 1..4 or curtain foot 5 or 0 plus 8 times the morph band, member slot
attribute vec2 a_height;  // this level's height, the parent level's height
attribute vec4 a_normal;  // normal xy at this level, at the parent level

uniform mat4 u_view_projection;
// Per member tile of the draw (a cluster's up to 16, or the one tile at
// slot 0), selected by the vertex's slot (a_grid.w):
// [6 slot]:     south-west post numbered from the anchor (xy), level-0 posts
//               per vertex post (z), skirt shares (w: bits 4(k-1) to 4k-1
//               for edge k, fifteenths of the skirt depth it hangs, 0 none;
//               bits 16 to 23 the skirt slope's code);
// [6 slot + 1]: morph start, morph end, skirt depth (the deepest), the
//               node centre's post row from the anchor (ellipsoid);
// [6 slot + 2]: the node centre's surface point from the camera (xyz,
//               camera axes), its post column from the anchor (w);
// [6 slot + 3]: the rotation from the centre's ENU axes to the camera's
//               (a unit quaternion xyzw). Zero in the chart.
// [6 slot + 4], [6 slot + 5]: a projected grid's node series: the centre's
//               latitude, then z, z^2, z^3's complex coefficients (xyz of
//               [6 slot + 5]); [6 slot + 5].w: the end of sub-level 1's
//               morph, which a vertex's band k >= 1 halves k - 1 times.
uniform vec4 u_members[96];
uniform vec4 u_posts;     // level-0 post spacing (xy), camera minus anchor post (zw), metres
uniform vec4 u_frame;     // camera altitude, 1 / (2 R) or 0 for a flat earth, the data's last post numbered from the anchor (zw)
// [0]: radians between posts east and north, the anchor row's latitude,
//      1 on the ellipsoid (0: the chart; 2: a projected grid, with
//      projected metres between posts over a in xy); [1]: semi-major axis,
//      e^2, the isometric latitude's e^2.
uniform vec4 u_earth[2];

varying vec3 v_normal;
varying float v_relative_height;  // terrain height minus aircraft altitude
varying float v_height;
varying float v_distance;
varying vec3 v_position;     // camera-relative, for the accuracy tool's position output
varying float v_no_data;     // 1 at a post without data, 0 elsewhere (see NO_DATA in the fragment shaders)
varying vec2 v_beyond;       // posts past the data's last post, east and north (clipped where above 0)
varying float v_curtain;     // above 0 on a curtain (the data's cut face, src/tiles/curtain.rs), 0 elsewhere

// The morph range of a vertex of morph band `band` (src/lod/morph.rs
// band_range, line for line): band 0 the tile's own, `own` (its level's
// morph toward the level above); band k >= 1 sub-level k's, toward
// sub-level k - 1: its end the tile's sub-level 1 end, `sub_end`, halved
// k - 1 times, its start that times `start_share` (every morph's start
// over its end, the frame's).
vec2 band_range(vec2 own, float sub_end, float start_share, float band) {
    if (band < 0.5) {
        return own;
    }
    float end = sub_end * exp2(1.0 - band);
    return vec2(end * start_share, end);
}

// sin d and 1 - cos d: by their series below half a radian, so a small
// angle keeps its digits whatever the GPU's sin does with it.
vec2 sin_hav(float d) {
    if (abs(d) > 0.5) {
        float half_sin = sin(0.5 * d);
        return vec2(sin(d), 2.0 * half_sin * half_sin);
    }
    float d2 = d * d;
    float s = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))));
    float h = d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (1.0 - d2 / 90.0))));
    return vec2(s, h);
}

vec2 complex_mul(vec2 a, vec2 b) {
    return vec2(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x);
}

// A projected grid's vertex at post number `post`: its longitude and
// latitude differences from its node's centre `centre` by the node's
// series `e0`, `e1` (NodePlace::projected_offsets).
vec2 projected_offsets(vec2 post, vec2 centre, vec4 e0, vec4 e1) {
    vec2 z = (post - centre) * u_earth[0].xy;
    vec2 w = complex_mul(z, vec2(e0.w, e1.x) + complex_mul(z, e1.yz));
    w = complex_mul(z, e0.yz + w);
    // Latitude from isometric latitude (expansion::latitude_series).
    float s0 = sin(e0.x);
    float c0 = cos(e0.x);
    float e2 = u_earth[1].z;
    float k = 1.0 / (1.0 - e2);
    float m = 1.0 - e2 * s0 * s0 + 2.0 * e2 * c0 * c0;
    float f = c0 * (1.0 - e2 * s0 * s0) * k;
    float f1 = -s0 * m * k;
    float f2 = (-c0 * m + 6.0 * e2 * s0 * s0 * c0) * k;
    float g3 = (f2 * f + f1 * f1) * f / 6.0;
    return vec2(w.x, w.y * (f + w.y * (f1 * f / 2.0 + w.y * g3)));
}

// The vertex whose latitude and longitude differ by `d` (east, north) from
// its node's centre at latitude `phi0`: its surface point (returned) and
// geodetic up (`up`), in the centre's east-north-up axes.
vec3 earth_local(float phi0, vec2 d, out vec3 up) {
    float a = u_earth[1].x;
    float e2 = u_earth[1].y;
    float s0 = sin(phi0);
    float c0 = cos(phi0);
    vec2 lam = sin_hav(d.x);
    vec2 phi = sin_hav(d.y);
    // sin and cos of the latitude, as changes from the centre's.
    float ds = c0 * phi.x - s0 * phi.y;
    float dc = -c0 * phi.y - s0 * phi.x;
    float s = s0 + ds;
    float c = c0 + dc;
    float k = ds * (2.0 * s0 + ds);
    float w0 = sqrt(1.0 - e2 * s0 * s0);
    float w = sqrt(1.0 - e2 * s0 * s0 - e2 * k);
    float n0 = a / w0;
    float dn = a * e2 * k / (w * w0 * (w + w0));
    // Minus the centre's surface point, in the centre meridian's axes
    // (x out at the equator, y east, z north).
    float dx = dn * c * (1.0 - lam.y) + n0 * dc * (1.0 - lam.y) - n0 * c0 * lam.y;
    float dy = (n0 + dn) * c * lam.x;
    float dz = dn * (1.0 - e2) * s + n0 * (1.0 - e2) * ds;
    up = vec3(c * lam.x, -s0 * c * (1.0 - lam.y) + c0 * s, c0 * c * (1.0 - lam.y) + s0 * s);
    return vec3(dy, -s0 * dx + c0 * dz, c0 * dx + s0 * dz);
}

// A vector of the node centre's ENU axes in the camera's (quaternion q).
vec3 rotate(vec4 q, vec3 v) {
    vec3 t = cross(q.xyz, v) + v * q.w;
    return v + 2.0 * cross(q.xyz, t);
}

void main() {
    int slot = int(a_grid.w);
    vec4 tile = u_members[6 * slot];
    vec4 ranges = u_members[6 * slot + 1];
    vec2 post = tile.xy + a_grid.xy * tile.z;
    // Linear across every triangle, so the clip at 0 is the data's edge.
    v_beyond = post - u_frame.zw;
    float altitude = u_frame.x;
    // A post without data carries tiles::NO_DATA (-1e9 m) and, as its target,
    // a real height nearby: its triangles are dropped, but stay small.
    bool no_data = a_height.x < -1.0e8;
    float own = no_data ? a_height.y : a_height.x;
    v_no_data = no_data ? 1.0 : 0.0;
    // Edge k hangs its skirt its share of the depth: 4-bit field k-1 of
    // tile.w (an integer below 2^16, exact in a highp float), fifteenths.
    // A curtain's foot (5) carries its own depth in its heights.
    // a_grid.z: the edge code in bits 0 to 2, the morph band above them.
    float code = mod(a_grid.z, 8.0);
    vec2 morph_band = band_range(ranges.xy, u_members[6 * slot + 5].w, u_earth[1].w,
                                 floor(a_grid.z / 8.0));
    bool skirt = code > 0.5 && code < 4.5;
    float share = skirt ? mod(floor(tile.w / exp2(4.0 * (code - 1.0))), 16.0) : 0.0;
    // Bits 16 to 23: the skirt slope's code (0: none), 128 + 8 log2 of the
    // metres a skirt may hang per metre of its distance, over 0.5 m
    // (render::draw_list::skirt_slope, SKIRT_BASE_M).
    float slope_code = floor(tile.w / 65536.0);
    float slope = slope_code > 0.5 ? exp2((slope_code - 128.0) / 8.0) : 1.0e30;
    v_curtain = code > 4.5 ? 1.0 : 0.0;
    vec2 n;
    vec3 p;
    float morph;
    float height;
    if (u_earth[0].w > 0.5) {
        vec4 place = u_members[6 * slot + 2];
        vec4 q = u_members[6 * slot + 3];
        vec2 centre = vec2(place.w, ranges.w);
        float phi0 = u_earth[0].z + centre.y * u_earth[0].y;
        vec2 d = (post - centre) * u_earth[0].xy;
        if (u_earth[0].w > 1.5) {
            vec4 e0 = u_members[6 * slot + 4];
            phi0 = e0.x;
            d = projected_offsets(post, centre, e0, u_members[6 * slot + 5]);
        }
        vec3 up;
        vec3 surface = earth_local(phi0, d, up);
        surface = rotate(q, surface) + place.xyz;
        up = rotate(q, up);
        float distance = length(surface + up * own);
        morph = clamp((distance - morph_band.x) / (morph_band.y - morph_band.x), 0.0, 1.0);
        height = mix(own, a_height.y, morph);
        float hang = min(share / 15.0 * ranges.z, slope * distance + 0.5);
        p = surface + up * (height - hang);
        n = mix(a_normal.xy, a_normal.zw, morph);
        // The tile's normal is in its own ENU axes: turned into the camera's.
        v_normal = rotate(q, vec3(n, sqrt(max(1.0 - dot(n, n), 0.0))));
    } else {
        vec2 position = post * u_posts.xy - u_posts.zw;
        float distance = length(vec3(position, own - altitude));
        morph = clamp((distance - morph_band.x) / (morph_band.y - morph_band.x), 0.0, 1.0);
        height = mix(own, a_height.y, morph);
        float drop = dot(position, position) * u_frame.y;
        float hang = min(share / 15.0 * ranges.z, slope * distance + 0.5);
        float z = height - hang - altitude - drop;
        p = vec3(position, z);
        n = mix(a_normal.xy, a_normal.zw, morph);
        v_normal = vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
    }
    v_relative_height = height - altitude;
    v_height = height;
    v_distance = length(p);
    v_position = p;
    gl_Position = u_view_projection * vec4(p, 1.0);
}
