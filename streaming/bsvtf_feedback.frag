#version 330 compatibility
// BSVTF feedback pass (streaming/StreamingGroup.h, Schwartz et al. 2013 section 3): which tile of
// which level of which streamed material every pixel shows. Drawn with common/btf.vert over the
// whole scene at a fraction of the screen's resolution into RGBA8: (tile x, tile y, level, material
// + 1) / 255; alpha 0 where no streamed material is (every other object, the background).
in vec2 btfTexCoord;

uniform int bsvtfMaterialId = -1;  // set by each streamed material; -1 for everything else
uniform ivec2 osgBTF_size;         // the material's finest texels
uniform ivec3 bsvtfTile;           // T, P, finest level L
// Screen pixels per feedback pixel along each axis: the derivatives here are that many times
// the screen's, and the level must be the one the screen needs.
uniform float bsvtfFeedbackScale = 1.0;

void main() {
    // Derivatives first, in uniform control flow.
    vec2 size = vec2(osgBTF_size);
    vec2 dx = dFdx(btfTexCoord) * size, dy = dFdy(btfTexCoord) * size;
    float texelsPerPixel = sqrt(max(dot(dx, dx), dot(dy, dy))) / bsvtfFeedbackScale;
    if (bsvtfMaterialId < 0) {
        gl_FragColor = vec4(0.0);
        return;
    }
    int L = bsvtfTile.z;
    // Schwartz et al. 2013 eq. 1, l = L - log2(texels per pixel), rounded to the finer level; the
    // small margin keeps exactly 2^k texels per pixel at L - k despite the derivatives' rounding.
    int level = L;
    if (texelsPerPixel > 1.0) level = L - int(floor(log2(texelsPerPixel) + 0.01));
    level = clamp(level, 0, L);
    ivec2 texel = clamp(ivec2(floor(fract(btfTexCoord) * size)), ivec2(0), osgBTF_size - 1);
    ivec2 tile = (texel >> (L - level)) / bsvtfTile.x;
    gl_FragColor = vec4(tile.x, tile.y, level, bsvtfMaterialId + 1) / 255.0;
}
