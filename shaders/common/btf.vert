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
}
