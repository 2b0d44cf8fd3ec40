#version 330 compatibility
// Shared vertex stage of every osgBTF material: passes the eye-space position and tangent frame
// so the fragment stage can express view and light directions in the surface's local frame
// (+Z normal, +X along texture s, +Y along texture t).

in vec4 osgBTF_tangent;  // xyz tangent along +s, w = handedness; (0,0,0,*) when absent
uniform float osgBTF_textureScale = 1.0;  // tiling: texture repeats per unit of texcoord

out vec2 btfTexCoord;
out vec3 btfEyePosition;
out vec3 btfEyeNormal;
out vec4 btfEyeTangent;

// Smooth shadow terminator (Sattler et al. 2003 sec. 4.3, scene/ShadowTerminator.h), per light:
// u = (1 + cos(alpha + angle(n, l))) / 2, looked up by btf_main.glsl in a blurred step texture.
// Per vertex, as in the paper, not per fragment: the boundary u = 0.5 then lies on each edge where
// the angles at its two vertices put it (Sattler et al. 2003, figure 9), so it runs straight
// across a coarse mesh instead of following the faceted silhouette, and it moves continuously
// with the light. A per-fragment u would instead follow the interpolated normal that the fragment
// stage already cuts at n.l = 0, and costs a cos and an acos per fragment and light.
const int osgBTF_maxLights = 8;
uniform int osgBTF_lightCount = 0;
uniform vec4 osgBTF_lightPosition[osgBTF_maxLights];
uniform bool osgBTF_terminator = false;
uniform float osgBTF_terminatorAlpha = 0.0;  // radians
out float btfTerminatorCoordinate[osgBTF_maxLights];

// Per-vertex occlusion of single lights (materials/LightVisibility.h): light i reads slot
// osgBTF_lightVisibilitySlot[i] of the three attributes' x, y, z; -1: seen.
in vec4 osgBTF_lightOcclusion0;
in vec4 osgBTF_lightOcclusion1;
in vec4 osgBTF_lightOcclusion2;
uniform int osgBTF_lightVisibilitySlot[osgBTF_maxLights];
out float btfLightVisibility[osgBTF_maxLights];

#ifdef OSGBTF_SHADOW_MAP
// The shadow technique's eye-linear TexGen on its texture unit (ShadowMap's, or the first map's
// of a ViewDependentShadowMap): planes already in eye space.
uniform int osgBTF_shadowTexGenUnit = 1;
out vec4 btfShadowCoordinate;
#endif

void main() {
    vec4 eye = gl_ModelViewMatrix * gl_Vertex;
    btfEyePosition = eye.xyz / eye.w;
    btfEyeNormal = gl_NormalMatrix * gl_Normal;
    // A tangent is a direction in the surface: it transforms like a position difference (the
    // modelview's upper 3x3), not like a normal. Under a non-uniform scale the normal matrix
    // would turn it away from the texture's s axis; btf_main.glsl re-orthogonalises it.
    btfEyeTangent = vec4(mat3(gl_ModelViewMatrix) * osgBTF_tangent.xyz, osgBTF_tangent.w);
    btfTexCoord = gl_MultiTexCoord0.st * osgBTF_textureScale;
    gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex;
    vec3 n = normalize(btfEyeNormal);
    vec3 occlusion[3] =
        vec3[3](osgBTF_lightOcclusion0.xyz, osgBTF_lightOcclusion1.xyz, osgBTF_lightOcclusion2.xyz);
    for (int i = 0; i < osgBTF_maxLights; ++i) {
        int slot = osgBTF_lightVisibilitySlot[i];
        btfLightVisibility[i] = slot < 0 || slot > 8 ? 1.0 : 1.0 - occlusion[slot / 3][slot % 3];
        btfTerminatorCoordinate[i] = 1.0;
        if (!osgBTF_terminator || i >= osgBTF_lightCount) continue;
        vec4 p = osgBTF_lightPosition[i];
        vec3 toLight = normalize(p.w == 0.0 ? p.xyz : p.xyz - btfEyePosition);
        float angle = acos(clamp(dot(n, toLight), -1.0, 1.0));
        btfTerminatorCoordinate[i] = 0.5 * (1.0 + cos(osgBTF_terminatorAlpha + angle));
    }
#ifdef OSGBTF_SHADOW_MAP
    int u = osgBTF_shadowTexGenUnit;
    btfShadowCoordinate = vec4(dot(eye, gl_EyePlaneS[u]), dot(eye, gl_EyePlaneT[u]),
                               dot(eye, gl_EyePlaneR[u]), dot(eye, gl_EyePlaneQ[u]));
#endif
}
