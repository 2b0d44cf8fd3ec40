// Shared fragment stage of environment lighting (materials/EnvironmentState.h): builds the local
// frame and view direction as btf_main.glsl does (same arithmetic, so the environment image
// lines up with the point-light one) and calls the method's btfEnvironmentEvaluate, which reads
// the folded per-vertex data through btfEnvData. Included after the #version line.

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

void main() {
    vec3 n = normalize(btfEyeNormal);
    vec3 t = btfEyeTangent.xyz - n * dot(n, btfEyeTangent.xyz);
    if (dot(t, t) < 1e-12) {
        t = abs(n.x) < 0.9 ? cross(vec3(1.0, 0.0, 0.0), n) : cross(vec3(0.0, 1.0, 0.0), n);
    }
    t = normalize(t);
    vec3 b = cross(n, t) * (btfEyeTangent.w < 0.0 ? -1.0 : 1.0);
    vec4 centre = -gl_ProjectionMatrixInverse[2];
    vec3 toEye = normalize(centre.xyz - centre.w * btfEyePosition);
    vec3 view = vec3(dot(toEye, t), dot(toEye, b), dot(toEye, n));
    if (osgBTF_fixedView.w > 0.5) view = normalize(osgBTF_fixedView.xyz);
    vec2 f = fract(btfTexCoord);
    ivec2 texel = clamp(ivec2(floor(f * vec2(osgBTF_size))), ivec2(0), osgBTF_size - ivec2(1));
    vec3 color = vec3(0.0);
    if (view.z > 0.0) color = osgBTF_envExposure * btfEnvironmentEvaluate(texel, view);
    gl_FragColor = vec4(color, 1.0);
}
