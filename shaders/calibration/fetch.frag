#version 330 compatibility
// Calibration pass of the comparison harness (harness/PassCost.h): N texelFetch reads of an
// RGBA32F texture per pixel, nothing else worth counting, so its time per pass gives the
// renderer's fetch rate. Coordinates step through the texture from the pixel's own position:
// neighbouring pixels read neighbouring texels (coherent, as a material tiled over a surface).
uniform sampler2D calibrationTexture;
uniform int calibrationFetches;

void main() {
    ivec2 size = textureSize(calibrationTexture, 0);
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec4 sum = vec4(0.0);
    for (int i = 0; i < calibrationFetches; ++i)
        sum += texelFetch(calibrationTexture, (p + ivec2(3 * i, 5 * i)) % size, 0);
    gl_FragColor = sum;
}
