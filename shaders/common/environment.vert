#version 330 compatibility
// Vertex stage of environment lighting (materials/EnvironmentState.h): btf.vert's outputs plus
// the vertex's index, which environment_geom.glsl hands to every fragment of the triangle so it
// can fetch the three vertices' folded environment data.

in vec4 osgBTF_tangent;  // xyz tangent along +s, w = handedness; (0,0,0,*) when absent
uniform float osgBTF_textureScale = 1.0;

out vec2 envTexCoord;
out vec3 envEyePosition;
out vec3 envEyeNormal;
out vec4 envEyeTangent;
flat out int envVertex;

void main() {
    vec4 eye = gl_ModelViewMatrix * gl_Vertex;
    envEyePosition = eye.xyz / eye.w;
    envEyeNormal = gl_NormalMatrix * gl_Normal;
    // As btf.vert: a tangent transforms by the modelview's upper 3x3, not the normal matrix.
    envEyeTangent = vec4(mat3(gl_ModelViewMatrix) * osgBTF_tangent.xyz, osgBTF_tangent.w);
    envTexCoord = gl_MultiTexCoord0.st * osgBTF_textureScale;
    // With glDrawElements gl_VertexID is the index value: the vertex's row in the data texture.
    envVertex = gl_VertexID;
    gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex;
}
