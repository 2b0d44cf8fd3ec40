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
// Exposure f of seed 004's T_j = f sum_k gamma*_kj B_kj: a uniform, so changing it is real-time.
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

/** Slot `slot` of the folded data, blended across the triangle (the seed's per-vertex data,
 *  interpolated as Gouraud shading would). */
vec3 btfEnvData(int slot) {
    return btfEnvBarycentric.x * btfEnvFetch(btfEnvVertices.x, slot) +
           btfEnvBarycentric.y * btfEnvFetch(btfEnvVertices.y, slot) +
           btfEnvBarycentric.z * btfEnvFetch(btfEnvVertices.z, slot);
}

// A fragment shows the bilinear blend, with wrap-around, of btfEnvironmentEvaluate at the four
// base texels around its texture coordinate (GL_LINEAR's weights, as btf_main.glsl's
// TexelFilter::Values at level 0; evaluateFoldedFiltered in materials/EnvironmentState.h is the
// CPU reference). The methods' environment shaders read their textures with texelFetch, so the
// blend of four evaluations is the one way that works for each of them unchanged. Minified
// fragments filter level 0 the same way (GL_LINEAR without mipmaps): a mip-mapped material's
// coarser levels are not read here.
void main() {
    vec3 t, b, n;
    btfSurfaceFrame(t, b, n);
    vec3 view = btfLocalView(t, b, n);
    vec3 color = vec3(0.0);
    if (view.z > 0.0) {
        ivec4 r = osgBTF_mipLevel[0];
        ivec2 i0, i1;
        vec2 w;
        btfBilinearNeighbours(btfTexCoord, r.zw, i0, i1, w);
        ivec2 texels[4] = ivec2[4](i0, ivec2(i1.x, i0.y), ivec2(i0.x, i1.y), i1);
        float weights[4] = float[4]((1.0 - w.x) * (1.0 - w.y), w.x * (1.0 - w.y),
                                    (1.0 - w.x) * w.y, w.x * w.y);
        for (int k = 0; k < 4; ++k)
            // A texel of weight 0 costs no evaluation (a texel centre, a rectified image).
            if (weights[k] > 0.0)
                color += weights[k] * btfEnvironmentEvaluate(r.xy + texels[k], view);
        color *= osgBTF_envExposure;
    }
    gl_FragColor = vec4(color, 1.0);
}
