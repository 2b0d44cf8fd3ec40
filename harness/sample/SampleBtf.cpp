#include "harness/sample/SampleBtf.h"

#include <cmath>

#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>
#include <glm/glm.hpp>

#include "core/Progress.h"

namespace osgBTF {

namespace {

constexpr float kPi = 3.14159265358979f;

struct Surface {
    int w, h;
    std::vector<float> height;      // in texel units
    std::vector<glm::vec3> normal;  // local frame
    std::vector<glm::vec3> albedo;
    std::vector<float> gloss;  // specular strength
    float maxHeight = 0;

    float heightAt(float x, float y) const {
        // Bilinear, wrapped: the sample tiles.
        x -= 0.5f;
        y -= 0.5f;
        const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
        const float fx = x - float(x0), fy = y - float(y0);
        auto at = [&](int xi, int yi) {
            xi = ((xi % w) + w) % w;
            yi = ((yi % h) + h) % h;
            return height[std::size_t(yi) * w + xi];
        };
        return (at(x0, y0) * (1 - fx) + at(x0 + 1, y0) * fx) * (1 - fy) +
               (at(x0, y0 + 1) * (1 - fx) + at(x0 + 1, y0 + 1) * fx) * fy;
    }
};

/** A value in [-1, 1] fixed by the cell and a salt (integer hash: the same on every platform). */
float cellNoise(int cu, int cv, unsigned salt) {
    unsigned x = unsigned(cu) * 73856093u ^ unsigned(cv) * 19349663u ^ salt * 83492791u;
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return float(x & 0xffffu) / 32767.5f - 1.0f;
}

Surface makeWeave(int w, int h, int threads, float variation) {
    Surface s{w, h, {}, {}, {}, {}, 0.0f};
    const std::size_t n = std::size_t(w) * h;
    s.height.resize(n);
    s.albedo.resize(n);
    s.gloss.resize(n);
    const float cells = float(threads * 2);
    const float amplitude = 0.06f * float(std::min(w, h)) / cells * 2.0f;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float u = (x + 0.5f) / w * cells, v = (y + 0.5f) / h * cells;
            const int cu = int(std::floor(u)), cv = int(std::floor(v));
            const float fu = u - cu, fv = v - cv;
            // Basket weave: in alternate cells the top thread runs along X or along Y.
            const bool alongX = ((cu + cv) & 1) == 0;
            const float across = alongX ? fv : fu, along = alongX ? fu : fv;
            const float profile = std::sin(kPi * across);               // round thread
            const float arch = 0.6f + 0.4f * std::sin(kPi * along);     // rises over the crossing
            const float ridges = 0.08f * std::sin(kPi * 6.0f * along);  // twisted fibres
            const std::size_t i = std::size_t(y) * w + x;
            const float lift = 1.0f + 0.3f * variation * cellNoise(cu, cv, 1);
            s.height[i] = lift * amplitude * (profile * arch + ridges * profile);
            s.albedo[i] = alongX ? glm::vec3(0.62f, 0.18f, 0.12f) : glm::vec3(0.85f, 0.72f, 0.35f);
            s.albedo[i] *= 0.75f + 0.25f * profile;
            if (variation > 0.0f)
                s.albedo[i] *=
                    glm::vec3(1.0f) +
                    0.35f * variation *
                        glm::vec3(cellNoise(cu, cv, 2), cellNoise(cu, cv, 3), cellNoise(cu, cv, 4));
            s.gloss[i] = alongX ? 0.25f : 0.12f;
        }
    }
    for (float v : s.height) s.maxHeight = std::max(s.maxHeight, v);
    s.normal.resize(n);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float dx = s.heightAt(x + 1.5f, y + 0.5f) - s.heightAt(x - 0.5f, y + 0.5f);
            const float dy = s.heightAt(x + 0.5f, y + 1.5f) - s.heightAt(x + 0.5f, y - 0.5f);
            s.normal[std::size_t(y) * w + x] =
                glm::normalize(glm::vec3(-dx * 0.5f, -dy * 0.5f, 1.0f));
        }
    }
    return s;
}

/** 1 when the light reaches the texel, 0 when the height field blocks it; a short soft edge
 *  near the occluder avoids aliasing in small samples. */
float lightVisibility(const Surface& s, int x, int y, const glm::vec3& l) {
    if (l.z >= 0.999f) return 1.0f;
    const float h0 = s.heightAt(x + 0.5f, y + 0.5f);
    const glm::vec2 dir = glm::normalize(glm::vec2(l.x, l.y));
    const float rise = l.z / std::sqrt(std::max(1e-8f, l.x * l.x + l.y * l.y));
    float visibility = 1.0f;
    const float maxDist = float(std::max(s.w, s.h));
    for (float t = 0.5f; t < maxDist; t += 0.5f) {
        const float rayHeight = h0 + t * rise;
        const float terrain = s.heightAt(x + 0.5f + dir.x * t, y + 0.5f + dir.y * t);
        visibility =
            std::min(visibility, std::clamp((rayHeight - terrain) / 0.3f + 0.5f, 0.0f, 1.0f));
        if (visibility <= 0.0f || rayHeight > s.maxHeight + 1.0f) break;
    }
    return visibility;
}

/** The texel whose surface the camera sees through reference-plane texel (x, y) from direction v:
 *  the first hit of the eye ray with the height field (mesostructure parallax and masking, the
 *  effect that makes measured BTFs view-dependent). */
std::size_t visibleTexel(const Surface& s, int x, int y, const glm::vec3& v) {
    const glm::vec2 start(x + 0.5f, y + 0.5f);
    auto wrapIndex = [&](glm::vec2 p) {
        const int xi = ((int(std::floor(p.x)) % s.w) + s.w) % s.w;
        const int yi = ((int(std::floor(p.y)) % s.h) + s.h) % s.h;
        return std::size_t(yi) * s.w + xi;
    };
    if (v.z >= 0.999f) return wrapIndex(start);
    // Walk from where the ray enters the height field's bounding slab down to the plane.
    const glm::vec2 slope = glm::vec2(v.x, v.y) / v.z;  // xy offset per unit of height
    const float step = 0.25f / std::max(1e-4f, glm::length(slope));
    for (float z = s.maxHeight; z > 0.0f; z -= step) {
        const glm::vec2 p = start + slope * z;
        if (s.heightAt(p.x, p.y) >= z) return wrapIndex(p);
    }
    return wrapIndex(start);
}

}  // namespace

MeasuredBtf makeSampleBtf(const SampleOptions& options) {
    MeasuredBtf btf(options.width, options.height, options.views, options.lights, options.storage);
    btf.source = "built-in sample (" + std::to_string(options.width) + "x" +
                 std::to_string(options.height) + ")";
    const Surface s =
        makeWeave(options.width, options.height, options.threadsPerTile, options.variation);
    const std::size_t texels = btf.texelCount();

    // Shadowing depends on texel and light only: compute it once per light.
    std::vector<float> shadow(btf.lightCount() * texels);
    Progress progress("sample", btf.lightCount() + btf.viewCount());
    tbb::parallel_for(std::size_t(0), btf.lightCount(), [&](std::size_t li) {
        const glm::vec3 l = btf.lights().vector(li);
        for (int y = 0; y < s.h; ++y)
            for (int x = 0; x < s.w; ++x) {
                float vis = 1.0f;
                // Stop marching once the ray is above the highest point.
                const float h0 = s.heightAt(x + 0.5f, y + 0.5f);
                if (h0 < s.maxHeight) vis = lightVisibility(s, x, y, l);
                shadow[li * texels + std::size_t(y) * s.w + x] = vis;
            }
        progress.advance();
    });

    tbb::parallel_for(std::size_t(0), btf.viewCount(), [&](std::size_t vi) {
        const glm::vec3 v = btf.views().vector(vi);
        std::vector<std::size_t> seen(texels);
        for (int y = 0; y < s.h; ++y)
            for (int x = 0; x < s.w; ++x) seen[std::size_t(y) * s.w + x] = visibleTexel(s, x, y, v);
        std::vector<float> image(texels * 3);
        for (std::size_t li = 0; li < btf.lightCount(); ++li) {
            const glm::vec3 l = btf.lights().vector(li);
            const glm::vec3 halfway = glm::normalize(v + l);
            for (std::size_t pixel = 0; pixel < texels; ++pixel) {
                const std::size_t t = seen[pixel];
                const glm::vec3& n = s.normal[t];
                const float cosL = std::max(0.0f, glm::dot(n, l));
                const float cosH = std::max(0.0f, glm::dot(n, halfway));
                // Fresnel-like rise toward grazing views makes the data view-dependent.
                const float fresnel = 0.04f + 0.96f * std::pow(1.0f - std::max(0.0f, v.z), 5.0f);
                const float specular = s.gloss[t] * (0.5f + fresnel) * std::pow(cosH, 40.0f);
                const float vis = shadow[li * texels + t];
                for (int c = 0; c < 3; ++c) {
                    const float value =
                        vis * cosL * (0.8f * s.albedo[t][c] + specular) + 0.02f * s.albedo[t][c];
                    image[pixel * 3 + c] = std::clamp(value, 0.0f, 1.0f);
                }
            }
            btf.setImage(vi, li, image.data());
        }
        progress.advance();
    });
    return btf;
}

}  // namespace osgBTF
