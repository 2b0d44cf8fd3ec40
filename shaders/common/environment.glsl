// Shared fragment stage of environment lighting (materials/EnvironmentState.h): builds the local
// frame and view direction with btf_main.glsl's functions (surface_frame.glsl, so the environment
// image lines up with the point-light one) and calls the method's btfEnvironmentEvaluate, which
// reads the folded per-vertex data through btfEnvData. Included after the #version line.

in vec2 btfTexCoord;
in vec3 btfEyePosition;
in vec3 btfEyeNormal;
in vec4 btfEyeTangent;
flat in ivec3 btfEnvVertices;
in vec3 btfEnvBarycentric;

uniform ivec2 osgBTF_size;
uniform vec4 osgBTF_fixedView = vec4(0.0);
// Exposure f of T_j = f sum_k gamma*_kj B_kj (Sattler et al. 2003): a uniform, so changing it is
// real-time.
uniform float osgBTF_envExposure = 1.0;
// Folded data, RGB float texels addressed linearly: vertex v's slot s is texel
// v * osgBTF_envStride + s, at column a % width, row a / width.
uniform sampler2D osgBTF_envData;
uniform int osgBTF_envStride;

vec3 btfEnvironmentEvaluate(ivec2 texel, vec3 view);

#pragma include "common/surface_frame.glsl"

vec3 btfEnvFetch(int vertex, int slot) {
    int a = vertex * osgBTF_envStride + slot;
    int w = textureSize(osgBTF_envData, 0).x;
    return texelFetch(osgBTF_envData, ivec2(a % w, a / w), 0).rgb;
}

/** Slot `slot` of the folded data, blended across the triangle (the per-vertex data of Sattler et
 *  al. 2003, interpolated as Gouraud shading would). */
vec3 btfEnvData(int slot) {
    return btfEnvBarycentric.x * btfEnvFetch(btfEnvVertices.x, slot) +
           btfEnvBarycentric.y * btfEnvFetch(btfEnvVertices.y, slot) +
           btfEnvBarycentric.z * btfEnvFetch(btfEnvVertices.z, slot);
}

// A fragment shows what point lights show of a texture coordinate (btf_main.glsl's
// TexelFilter::Values, surface_frame.glsl's btfAddMipTaps): the bilinear blend, with wrap-around,
// of btfEnvironmentEvaluate at the four texels around it, and for a minified mip-mapped material
// the blend of two levels' such lookups by the level of detail (GL_LINEAR_MIPMAP_LINEAR), up to
// 8 evaluations; evaluateFoldedFiltered in materials/EnvironmentState.h is the CPU reference.
// The methods' environment shaders read their textures with texelFetch, so the blend of the
// evaluations is the one way that works for each of them unchanged; without the coarser levels a
// distant surface would alias (moire) under environment lighting only.
void main() {
    vec3 t, b, n;
    btfSurfaceFrame(t, b, n);
    vec3 view = btfLocalView(t, b, n);
    // Before any branch: the level of detail takes derivatives.
    btfAddMipTaps(btfTexCoord, true);
    vec3 color = vec3(0.0);
    if (view.z > 0.0) {
        for (int k = 0; k < btfTapCount; ++k)
            color += btfTapWeight(k) * btfEnvironmentEvaluate(btfTapTexel(k), view);
        color *= osgBTF_envExposure;
    }
    gl_FragColor = vec4(color, 1.0);
}
