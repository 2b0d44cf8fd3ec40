#include "materials/EnvironmentLighting.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "materials/Material.h"

namespace osgBTF {

namespace {

constexpr double kPi = 3.14159265358979323846;

glm::vec3 toLocal(const SurfaceFrame& frame, const glm::vec3& world) {
    return glm::vec3(glm::dot(world, frame.tangent), glm::dot(world, frame.bitangent),
                     glm::dot(world, frame.normal));
}

}  // namespace

EnvironmentMap EnvironmentMap::constant(const glm::vec3& radiance) {
    EnvironmentMap map;
    map.width = map.height = 1;
    map.rgb = {radiance.x, radiance.y, radiance.z};
    return map;
}

glm::vec3 EnvironmentMap::texel(int column, int row) const {
    const float* p = rgb.data() + (std::size_t(row) * std::size_t(width) + std::size_t(column)) * 3;
    return glm::vec3(p[0], p[1], p[2]);
}

double EnvironmentMap::solidAngle(int row) const {
    const double theta0 = kPi * double(height - 1 - row) / height;
    const double theta1 = kPi * double(height - row) / height;
    return 2.0 * kPi / width * (std::cos(theta0) - std::cos(theta1));
}

glm::vec3 EnvironmentMap::direction(double u, double v) const {
    const double theta = kPi * (1.0 - v / height);
    const double phi = 2.0 * kPi * u / width + double(rotationDegrees) * kPi / 180.0;
    return glm::vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                     float(std::cos(theta)));
}

glm::vec3 EnvironmentMap::radiance(const glm::vec3& d) const {
    const double theta = std::acos(std::clamp(double(d.z) / glm::length(d), -1.0, 1.0));
    double phi = std::atan2(double(d.y), double(d.x)) - double(rotationDegrees) * kPi / 180.0;
    phi -= 2.0 * kPi * std::floor(phi / (2.0 * kPi));
    const int column = std::clamp(int(phi / (2.0 * kPi) * width), 0, width - 1);
    const int row = std::clamp(int(height * (1.0 - theta / kPi)), 0, height - 1);
    return texel(column, row);
}

EnvironmentMap EnvironmentMap::downsampled(int newWidth) const {
    if (newWidth < 2) throw Error("environment: projection width must be at least 2");
    if (newWidth >= width) return *this;
    const int newHeight = std::max(1, newWidth / 2);
    if (width % newWidth != 0 || height % newHeight != 0)
        throw Error("environment: a " + std::to_string(width) + " x " + std::to_string(height) +
                    " map cannot be averaged down to " + std::to_string(newWidth) + " x " +
                    std::to_string(newHeight) + " (not a whole number of texels per texel)");
    const int fx = width / newWidth, fy = height / newHeight;
    EnvironmentMap out;
    out.width = newWidth;
    out.height = newHeight;
    out.rotationDegrees = rotationDegrees;
    out.rgb.assign(std::size_t(newWidth) * std::size_t(newHeight) * 3, 0.0f);
    for (int r = 0; r < newHeight; ++r)
        for (int c = 0; c < newWidth; ++c) {
            glm::dvec3 sum(0.0);
            double omega = 0;
            for (int y = r * fy; y < (r + 1) * fy; ++y)
                for (int x = c * fx; x < (c + 1) * fx; ++x) {
                    const double o = solidAngle(y);
                    sum += glm::dvec3(texel(x, y)) * o;
                    omega += o;
                }
            float* p = out.rgb.data() + (std::size_t(r) * std::size_t(newWidth) + c) * 3;
            for (int ch = 0; ch < 3; ++ch) p[ch] = float(sum[ch] / omega);
        }
    return out;
}

namespace {

/** The range of dot(d, n) over texel (c, r). A linear function's extremes on a lat-long
 *  rectangle lie at its corners, where an edge runs tangent to the function's level lines, or at
 *  +-n inside it, so those few points give the exact range. */
void normalRange(const EnvironmentMap& map, int c, int r, const glm::vec3& normal, double& lo,
                 double& hi) {
    const double nx = normal.x, ny = normal.y, nz = normal.z;
    const double theta0 = kPi * double(map.height - 1 - r) / map.height;
    const double theta1 = kPi * double(map.height - r) / map.height;
    const double phi0 = 2.0 * kPi * c / map.width + double(map.rotationDegrees) * kPi / 180.0;
    const double dphi = 2.0 * kPi / map.width;
    lo = 2, hi = -2;
    auto f = [&](double theta, double phi) {
        const double v =
            std::sin(theta) * (nx * std::cos(phi) + ny * std::sin(phi)) + nz * std::cos(theta);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    };
    auto inPhi = [&](double phi) {
        const double d = phi - phi0 - 2.0 * kPi * std::floor((phi - phi0) / (2.0 * kPi));
        return d <= dphi;
    };
    const double phiN = std::atan2(ny, nx);
    for (double theta : {theta0, theta1}) {
        for (double phi : {phi0, phi0 + dphi}) f(theta, phi);
        for (double phi : {phiN, phiN + kPi})
            if (inPhi(phi)) f(theta, phi);
    }
    for (double phi : {phi0, phi0 + dphi}) {
        const double a = nx * std::cos(phi) + ny * std::sin(phi);
        const double t = std::atan2(a, nz);
        for (double theta : {t, t + kPi, t - kPi})
            if (theta >= theta0 && theta <= theta1) f(theta, phi);
    }
    const double thetaN = std::acos(std::clamp(nz, -1.0, 1.0));
    if (thetaN >= theta0 && thetaN <= theta1 && inPhi(phiN)) hi = 1;
    if (kPi - thetaN >= theta0 && kPi - thetaN <= theta1 && inPhi(phiN + kPi)) lo = -1;
}

}  // namespace

int horizonSplit(int width) {
    return std::max(1, (512 + width - 1) / std::max(1, width));
}

std::vector<EnvironmentSample> visibleEnvironment(const EnvironmentMap& map,
                                                  const SurfaceFrame& frame,
                                                  const OcclusionTest& occluded) {
    if (map.width < 1 || map.height < 1 ||
        map.rgb.size() != std::size_t(map.width) * std::size_t(map.height) * 3)
        throw Error("environment: empty or inconsistent map");
    std::vector<EnvironmentSample> samples;
    const int split = horizonSplit(map.width);
    auto add = [&](const glm::vec3& world, double omega, const glm::vec3& radiance) {
        const glm::vec3 local = toLocal(frame, world);
        if (!(local.z > 0.0f)) return;
        if (occluded && occluded(frame.position, world)) return;
        samples.push_back({glm::normalize(local), omega, radiance});
    };
    // Centre directions from per-column and per-row sines and cosines (no trigonometry per
    // texel); a texel farther from the horizon than its row's reach (the largest angle from its
    // centre to its corners and edge midpoints, the same for every column) is whole on one side,
    // and only the others need the exact range.
    std::vector<double> cosPhi(std::size_t(map.width)), sinPhi(std::size_t(map.width));
    for (int c = 0; c < map.width; ++c) {
        const double phi =
            2.0 * kPi * (c + 0.5) / map.width + double(map.rotationDegrees) * kPi / 180.0;
        cosPhi[std::size_t(c)] = std::cos(phi);
        sinPhi[std::size_t(c)] = std::sin(phi);
    }
    for (int r = 0; r < map.height; ++r) {
        const double theta0 = kPi * double(map.height - 1 - r) / map.height;
        const double theta1 = kPi * double(map.height - r) / map.height;
        const double sinTheta = std::sin(0.5 * (theta0 + theta1));
        const double cosTheta = std::cos(0.5 * (theta0 + theta1));
        double reach = 0;
        {
            const glm::vec3 centre = map.direction(0.5, r + 0.5);
            for (double du : {0.0, 0.5, 1.0})
                for (double dv : {0.0, 0.5, 1.0}) {
                    const double d = glm::dot(centre, map.direction(du, r + dv));
                    reach = std::max(reach, std::acos(std::clamp(d, -1.0, 1.0)));
                }
        }
        const double margin = std::sin(std::min(kPi / 2, reach * 1.05 + 1e-6));
        for (int c = 0; c < map.width; ++c) {
            const glm::vec3 radiance = map.texel(c, r);
            const glm::vec3 centre(float(sinTheta * cosPhi[std::size_t(c)]),
                                   float(sinTheta * sinPhi[std::size_t(c)]), float(cosTheta));
            const double elevation = glm::dot(centre, frame.normal);  // sine of it
            if (elevation > margin) {
                add(centre, map.solidAngle(r), radiance);
                continue;
            }
            if (elevation < -margin) continue;
            double lo = 0, hi = 0;
            normalRange(map, c, r, frame.normal, lo, hi);
            // Boundaries that lie on the horizon (a surface facing +Z, an even map height) leave
            // rounding-sized values on the wrong side: those texels are not split.
            if (hi <= 1e-9) continue;
            if (lo >= -1e-9) {
                add(centre, map.solidAngle(r), radiance);
                continue;
            }
            // Parts equal in azimuth and in cos(theta), so each has the exact solid angle of its
            // own piece of the sphere.
            const double cos0 = std::cos(theta0), cos1 = std::cos(theta1);
            const double omega = 2.0 * kPi / map.width / split * (cos0 - cos1) / split;
            for (int j = 0; j < split; ++j) {
                const double z = cos1 + (cos0 - cos1) * (j + 0.5) / split;
                const double v = map.height * (1.0 - std::acos(z) / kPi);
                for (int i = 0; i < split; ++i)
                    add(map.direction(c + (i + 0.5) / split, v), omega, radiance);
            }
        }
    }
    return samples;
}

std::vector<glm::vec3> projectEnvironment(const std::vector<EnvironmentSample>& samples,
                                          const DirectionInterpolator& lights) {
    std::vector<glm::dvec3> sum(lights.directionCount(), glm::dvec3(0.0));
    for (const EnvironmentSample& s : samples) {
        const InterpolationWeights w = lights.weights(s.local);
        for (int m = 0; m < 3; ++m)
            if (w.weight[m] > 0.0f)
                sum[std::size_t(w.index[m])] +=
                    glm::dvec3(s.radiance) * (s.solidAngle * double(w.weight[m]));
    }
    return std::vector<glm::vec3>(sum.begin(), sum.end());
}

std::vector<glm::vec3> projectEnvironment(const std::vector<EnvironmentSample>& samples,
                                          const DirectionTable& table, std::size_t lightCount) {
    std::vector<glm::dvec3> sum(lightCount, glm::dvec3(0.0));
    for (const EnvironmentSample& s : samples) {
        const InterpolationWeights w = DirectionInterpolator::lookupTable(table, s.local);
        for (int m = 0; m < 3; ++m)
            if (w.weight[m] > 0.0f && std::size_t(w.index[m]) < lightCount)
                sum[std::size_t(w.index[m])] +=
                    glm::dvec3(s.radiance) * (s.solidAngle * double(w.weight[m]));
    }
    return std::vector<glm::vec3>(sum.begin(), sum.end());
}

glm::vec3 environmentReference(const Material& material, int x, int y, const glm::vec3& view,
                               const std::vector<EnvironmentSample>& samples) {
    glm::dvec3 sum(0.0);
    for (const EnvironmentSample& s : samples)
        sum += glm::dvec3(s.radiance * material.evaluate(x, y, view, s.local)) * s.solidAngle;
    return glm::vec3(sum);
}

void checkProjected(const Material& material, const std::vector<glm::vec3>& g) {
    if (g.size() != material.lights().size())
        throw Error("environment: " + std::to_string(g.size()) + " projected values for " +
                    std::to_string(material.lights().size()) + " measured light directions");
}

glm::vec3 evaluateProjected(const Material& material, int x, int y, const glm::vec3& view,
                            const std::vector<glm::vec3>& g) {
    checkProjected(material, g);
    glm::dvec3 sum(0.0);
    for (std::size_t i = 0; i < g.size(); ++i)
        if (g[i] != glm::vec3(0.0f))
            sum += glm::dvec3(g[i] * material.evaluate(x, y, view, material.lights().vector(i)));
    return glm::vec3(sum);
}

namespace {

struct Region {
    int c0, c1, r0, r1;  ///< texel columns [c0, c1), rows [r0, r1)
};

}  // namespace

std::vector<RepresentativeLight> medianCutLights(const EnvironmentMap& map, int count) {
    if (count < 1 || count > 1024 || (count & (count - 1)) != 0)
        throw Error("environment: representative light count " + std::to_string(count) +
                    " is not a power of two between 1 and 1024");
    if (map.width < 1 || map.height < 1) throw Error("environment: empty map");
    // Luminance times solid angle per texel: what the cuts balance.
    std::vector<double> energy(std::size_t(map.width) * std::size_t(map.height));
    for (int r = 0; r < map.height; ++r)
        for (int c = 0; c < map.width; ++c) {
            const glm::vec3 t = map.texel(c, r);
            energy[std::size_t(r) * map.width + c] =
                (0.2126 * t.x + 0.7152 * t.y + 0.0722 * t.z) * map.solidAngle(r);
        }
    std::vector<Region> regions{{0, map.width, 0, map.height}};
    while (int(regions.size()) < count) {
        std::vector<Region> next;
        for (const Region& g : regions) {
            const double latitude = kPi * (0.5 - 0.5 * (g.r0 + g.r1) / map.height);
            const double width = double(g.c1 - g.c0) / map.width * 2.0 * std::cos(latitude);
            const double height = double(g.r1 - g.r0) / map.height;
            const bool alongColumns = (width >= height && g.c1 - g.c0 > 1) || g.r1 - g.r0 < 2;
            const int lo = alongColumns ? g.c0 : g.r0, hi = alongColumns ? g.c1 : g.r1;
            if (hi - lo < 2) {  // a single texel cannot be cut: it stays one light
                next.push_back(g);
                continue;
            }
            std::vector<double> line(std::size_t(hi - lo), 0.0);
            for (int r = g.r0; r < g.r1; ++r)
                for (int c = g.c0; c < g.c1; ++c)
                    line[std::size_t((alongColumns ? c : r) - lo)] +=
                        energy[std::size_t(r) * map.width + c];
            double total = 0;
            for (double e : line) total += e;
            int cut = lo + 1;
            double running = line[0];
            while (cut < hi - 1 && running + line[std::size_t(cut - lo)] <= total / 2)
                running += line[std::size_t(cut++ - lo)];
            Region a = g, b = g;
            if (alongColumns)
                a.c1 = b.c0 = cut;
            else
                a.r1 = b.r0 = cut;
            next.push_back(a);
            next.push_back(b);
        }
        if (next.size() == regions.size()) break;  // every region is one texel
        regions = std::move(next);
    }
    std::vector<RepresentativeLight> lights;
    for (const Region& g : regions) {
        glm::dvec3 power(0.0), centroid(0.0);
        for (int r = g.r0; r < g.r1; ++r)
            for (int c = g.c0; c < g.c1; ++c) {
                const double omega = map.solidAngle(r);
                const double e = energy[std::size_t(r) * map.width + c];
                power += glm::dvec3(map.texel(c, r)) * omega;
                centroid += glm::dvec3(map.direction(c + 0.5, r + 0.5)) * e;
            }
        const double length = glm::length(centroid);
        const glm::vec3 direction = length > 0
                                        ? glm::vec3(centroid / length)
                                        : map.direction(0.5 * (g.c0 + g.c1), 0.5 * (g.r0 + g.r1));
        lights.push_back({direction, glm::vec3(power)});
    }
    return lights;
}

glm::vec3 evaluateRepresentative(const Material& material, int x, int y, const glm::vec3& view,
                                 const SurfaceFrame& frame,
                                 const std::vector<RepresentativeLight>& lights,
                                 const OcclusionTest& occluded) {
    glm::vec3 sum(0.0f);
    for (const RepresentativeLight& light : lights) {
        const glm::vec3 local = toLocal(frame, light.direction);
        if (!(local.z > 0.0f)) continue;
        if (occluded && occluded(frame.position, light.direction)) continue;
        sum += light.power * material.evaluate(x, y, view, glm::normalize(local));
    }
    return sum;
}

}  // namespace osgBTF
