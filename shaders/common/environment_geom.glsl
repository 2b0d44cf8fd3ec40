#version 330 compatibility
// Geometry stage of environment lighting: passes the triangle through and gives each fragment
// the triangle's three vertex indices (flat) and its barycentric coordinates, so the folded
// per-vertex data are blended across the triangle in the fragment stage. Per-vertex data for all
// blended views are far too large for varyings (81 views x 17 slots x RGB per vertex for pca).

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

in vec2 envTexCoord[];
in vec3 envEyePosition[];
in vec3 envEyeNormal[];
in vec4 envEyeTangent[];
flat in int envVertex[];

out vec2 btfTexCoord;
out vec3 btfEyePosition;
out vec3 btfEyeNormal;
out vec4 btfEyeTangent;
flat out ivec3 btfEnvVertices;
out vec3 btfEnvBarycentric;

void main() {
    for (int i = 0; i < 3; ++i) {
        gl_Position = gl_in[i].gl_Position;
        btfTexCoord = envTexCoord[i];
        btfEyePosition = envEyePosition[i];
        btfEyeNormal = envEyeNormal[i];
        btfEyeTangent = envEyeTangent[i];
        btfEnvVertices = ivec3(envVertex[0], envVertex[1], envVertex[2]);
        btfEnvBarycentric = vec3(i == 0 ? 1.0 : 0.0, i == 1 ? 1.0 : 0.0, i == 2 ? 1.0 : 0.0);
        EmitVertex();
    }
    EndPrimitive();
}
