#include "harness/Pictures.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <osg/Geode>
#include <osg/Uniform>

#include "core/Error.h"
#include "core/ImageCodecs.h"
#include "harness/MaterialImage.h"
#include "harness/PassCost.h"

namespace osgBTF {

osg::ref_ptr<osg::Geometry> createTangentSphere(int segments, int rings) {
    if (segments < 3 || rings < 2) throw Error("createTangentSphere: too few segments or rings");
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texcoords = new osg::Vec2Array;
    osg::ref_ptr<osg::Vec4Array> tangents = new osg::Vec4Array;
    const double pi = osg::PI;
    // Poles on -Y / +Y; s = 0 faces +Z. Duplicate seam column so s runs 0..1 without wrapping.
    for (int r = 0; r <= rings; ++r) {
        const double theta = pi * double(r) / rings;  // 0 at the south pole
        for (int s = 0; s <= segments; ++s) {
            const double phi = 2.0 * pi * double(s) / segments;
            const osg::Vec3 n(float(std::sin(theta) * std::sin(phi)), float(-std::cos(theta)),
                              float(std::sin(theta) * std::cos(phi)));
            vertices->push_back(n);
            normals->push_back(n);
            texcoords->push_back(osg::Vec2(float(double(s) / segments), float(double(r) / rings)));
            // d(position)/d(phi), normalised: the direction of increasing s (also at the poles).
            tangents->push_back(osg::Vec4(float(std::cos(phi)), 0.0f, float(-std::sin(phi)), 1.0f));
        }
    }
    osg::ref_ptr<osg::DrawElementsUInt> triangles =
        new osg::DrawElementsUInt(osg::PrimitiveSet::TRIANGLES);
    const int columns = segments + 1;
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const unsigned a = unsigned(r * columns + s), b = a + 1, c = a + unsigned(columns),
                           d = c + 1;
            for (unsigned index : {a, b, d, a, d, c}) triangles->push_back(index);
        }
    osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
    geometry->setVertexArray(vertices.get());
    geometry->setNormalArray(normals.get(), osg::Array::BIND_PER_VERTEX);
    geometry->setTexCoordArray(0, texcoords.get(), osg::Array::BIND_PER_VERTEX);
    geometry->setVertexAttribArray(6, tangents.get(), osg::Array::BIND_PER_VERTEX);
    geometry->addPrimitiveSet(triangles.get());
    geometry->setUseDisplayList(false);
    geometry->setUseVertexBufferObjects(true);
    return geometry;
}

std::vector<SphereSetting> defaultSphereSettings() {
    return {{"front light", 0.0f, osg::Vec3(-0.4f, 0.5f, 0.77f)},
            {"grazing light", 0.0f, osg::Vec3(0.95f, 0.15f, 0.25f)},
            {"seen from 50 degrees above, light from the upper left", 50.0f,
             osg::Vec3(-0.7f, 0.6f, 0.4f)}};
}

CameraSetup sphereCamera(const SphereSetting& setting, int size) {
    const double e = osg::DegreesToRadians(double(setting.cameraElevation));
    const double distance = 3.2;
    CameraSetup camera;
    camera.view =
        osg::Matrixd::lookAt(osg::Vec3d(0, distance * std::sin(e), distance * std::cos(e)),
                             osg::Vec3d(0, 0, 0), osg::Vec3d(0, std::cos(e), -std::sin(e)));
    camera.projection = osg::Matrixd::perspective(40.0, 1.0, 0.5, 10.0);
    camera.width = camera.height = size;
    return camera;
}

FloatImage renderSphere(HeadlessRenderer& renderer, const Material& material,
                        const SphereSetting& setting, int size, float textureScale) {
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    setDirectionalLights(*stateSet, {setting.lightDirection});
    stateSet->getOrCreateUniform("osgBTF_textureScale", osg::Uniform::FLOAT)->set(textureScale);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(createTangentSphere().get());
    geode->setStateSet(stateSet.get());

    osg::ref_ptr<osg::Image> image = renderer.render(geode.get(), sphereCamera(setting, size));
    renderer.setScene(nullptr);
    return rgbTopDown(*image, size, size);
}

FloatImage enlarge(const FloatImage& image, int factor) {
    if (factor <= 1) return image;
    FloatImage out(image.width * factor, image.height * factor, image.channels);
    out.channelNames = image.channelNames;
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < image.channels; ++c)
                out.at(x, y, c) = image.at(x / factor, y / factor, c);
    return out;
}

FloatImage tileImages(const std::vector<std::vector<FloatImage>>& rows, int gap, float fill) {
    int cellW = 0, cellH = 0;
    std::size_t columns = 0;
    for (const auto& row : rows) {
        columns = std::max(columns, row.size());
        for (const FloatImage& image : row) {
            cellW = std::max(cellW, image.width);
            cellH = std::max(cellH, image.height);
        }
    }
    const int w = int(columns) * cellW + (int(columns) - 1) * gap;
    const int h = int(rows.size()) * cellH + (int(rows.size()) - 1) * gap;
    FloatImage out(std::max(w, 1), std::max(h, 1), 3);
    out.channelNames = {"R", "G", "B"};
    std::fill(out.pixels.begin(), out.pixels.end(), fill);
    for (std::size_t r = 0; r < rows.size(); ++r)
        for (std::size_t i = 0; i < rows[r].size(); ++i) {
            const FloatImage& image = rows[r][i];
            const int x0 = int(i) * (cellW + gap), y0 = int(r) * (cellH + gap);
            for (int y = 0; y < image.height; ++y)
                for (int x = 0; x < image.width; ++x)
                    for (int c = 0; c < 3; ++c)
                        out.at(x0 + x, y0 + y, c) = image.at(x, y, std::min(c, image.channels - 1));
        }
    return out;
}

FloatImage stackImages(const FloatImage& top, const FloatImage& bottom, int gap, float fill) {
    FloatImage out(std::max(top.width, bottom.width), top.height + gap + bottom.height, 3);
    out.channelNames = {"R", "G", "B"};
    std::fill(out.pixels.begin(), out.pixels.end(), fill);
    int y0 = 0;
    for (const FloatImage* image : {&top, &bottom}) {
        for (int y = 0; y < image->height; ++y)
            for (int x = 0; x < image->width; ++x)
                for (int c = 0; c < 3; ++c)
                    out.at(x, y0 + y, c) = image->at(x, y, std::min(c, image->channels - 1));
        y0 += image->height + gap;
    }
    return out;
}

FloatImage addTopBand(const FloatImage& image, int height, float fill) {
    FloatImage out(image.width, image.height + height, image.channels);
    out.channelNames = image.channelNames;
    std::fill(out.pixels.begin(), out.pixels.end(), fill);
    std::copy(image.pixels.begin(), image.pixels.end(),
              out.pixels.begin() + std::ptrdiff_t(out.index(0, height, 0)));
    return out;
}

bool drawText(FloatImage& image, int x, int y, const std::string& text, int size, float value) {
    return imageCodecs().drawText(image, x, y, text, size, value);
}

glm::vec3 colourMap(float t) {
    // Viridis at 9 evenly spaced stops, linearly interpolated.
    static const glm::vec3 stops[] = {
        {0.267f, 0.005f, 0.329f}, {0.279f, 0.175f, 0.483f}, {0.230f, 0.322f, 0.546f},
        {0.173f, 0.449f, 0.558f}, {0.128f, 0.567f, 0.551f}, {0.158f, 0.684f, 0.502f},
        {0.369f, 0.789f, 0.383f}, {0.678f, 0.864f, 0.190f}, {0.993f, 0.906f, 0.144f}};
    if (!(t > 0.0f)) return stops[0];
    if (t >= 1.0f) return stops[8];
    const float f = t * 8.0f;
    const int i = std::min(int(f), 7);
    return stops[i] + (stops[i + 1] - stops[i]) * (f - float(i));
}

FloatImage colourMappedErrors(const std::vector<float>& perTexel, int width, int height,
                              double maxValue) {
    if (perTexel.size() != std::size_t(width) * std::size_t(height))
        throw Error("colourMappedErrors: " + std::to_string(perTexel.size()) + " values for a " +
                    std::to_string(width) + "x" + std::to_string(height) + " map");
    FloatImage out(width, height, 3);
    out.channelNames = {"R", "G", "B"};
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const float v = perTexel[std::size_t(y) * width + x];
            const glm::vec3 c = std::isfinite(v)
                                    ? colourMap(maxValue > 0 ? float(v / maxValue) : 0.0f)
                                : std::isnan(v) ? glm::vec3(0.5f)  // not compared
                                                : glm::vec3(1, 0, 1);
            for (int k = 0; k < 3; ++k) out.at(x, height - 1 - y, k) = c[k];
        }
    return out;
}

FloatImage colourBar(int width, int height) {
    FloatImage out(width, height, 3);
    out.channelNames = {"R", "G", "B"};
    for (int x = 0; x < width; ++x) {
        const glm::vec3 c = colourMap(width > 1 ? float(x) / float(width - 1) : 0.0f);
        for (int y = 0; y < height; ++y)
            for (int k = 0; k < 3; ++k) out.at(x, y, k) = c[k];
    }
    return out;
}

FloatImage measuredImage(const BtfSource& btf, std::size_t view, std::size_t light) {
    std::vector<float> rgb(btf.texelCount() * 3);
    btf.readImages(view * btf.lightCount() + light, 1, rgb.data());
    const int w = btf.width(), h = btf.height();
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                out.at(x, h - 1 - y, c) = rgb[(std::size_t(y) * w + x) * 3 + c];
    return out;
}

std::size_t nearestDirection(const DirectionSet& set, float theta, float phi) {
    const glm::vec3 wanted = Direction{theta, phi}.toVector();
    std::size_t best = 0;
    float bestDot = -2.0f;
    for (std::size_t i = 0; i < set.size(); ++i) {
        const glm::vec3 v = set.vector(i);
        const float d = v.x * wanted.x + v.y * wanted.y + v.z * wanted.z;
        if (d > bestDot) {
            bestDot = d;
            best = i;
        }
    }
    return best;
}

namespace {
std::string escapeXml(const std::string& text) {
    std::string out;
    for (char c : text) {
        if (c == '<')
            out += "&lt;";
        else if (c == '>')
            out += "&gt;";
        else if (c == '&')
            out += "&amp;";
        else if (c == '"')
            out += "&quot;";
        else
            out += c;
    }
    return out;
}
}  // namespace

std::string errorMemorySvg(const std::vector<PlotPoint>& points, const std::string& title) {
    const double width = 720, height = 440, left = 80, right = 30, top = 40, bottom = 60;
    const double plotW = width - left - right, plotH = height - top - bottom;
    double minBytes = 1e300, maxBytes = 0, maxError = 0;
    for (const PlotPoint& p : points) {
        if (!(p.bytesPerTexel > 0) || !std::isfinite(p.error)) continue;
        minBytes = std::min(minBytes, p.bytesPerTexel);
        maxBytes = std::max(maxBytes, p.bytesPerTexel);
        maxError = std::max(maxError, p.error);
    }
    if (maxBytes <= 0) minBytes = 1, maxBytes = 10;
    const double lo = std::floor(std::log10(minBytes)),
                 hi = std::max(lo + 1, std::ceil(std::log10(maxBytes)));
    if (!(maxError > 0)) maxError = 1;
    const double yMax = maxError * 1.15;
    auto px = [&](double bytes) { return left + (std::log10(bytes) - lo) / (hi - lo) * plotW; };
    auto py = [&](double error) { return top + plotH - error / yMax * plotH; };

    std::ostringstream svg;
    svg << std::setprecision(4);
    svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
        << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
        << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
        << "<text x=\"" << width / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">"
        << escapeXml(title) << "</text>\n"
        << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << plotW << "\" height=\""
        << plotH << "\" fill=\"none\" stroke=\"black\"/>\n";
    for (double decade = lo; decade <= hi + 1e-9; decade += 1) {
        const double x = left + (decade - lo) / (hi - lo) * plotW;
        svg << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\""
            << top + plotH << "\" stroke=\"#ddd\"/>\n"
            << "<text x=\"" << x << "\" y=\"" << top + plotH + 18 << "\" text-anchor=\"middle\">"
            << std::pow(10.0, decade) << "</text>\n";
    }
    for (int i = 0; i <= 4; ++i) {
        const double e = yMax * i / 4.0, y = py(e);
        svg << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << left + plotW << "\" y2=\""
            << y << "\" stroke=\"#ddd\"/>\n"
            << "<text x=\"" << left - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << e
            << "</text>\n";
    }
    svg << "<text x=\"" << left + plotW / 2 << "\" y=\"" << height - 15
        << "\" text-anchor=\"middle\">bytes per texel (log scale)</text>\n"
        << "<text x=\"18\" y=\"" << top + plotH / 2
        << "\" text-anchor=\"middle\" transform=\"rotate(-90 18 " << top + plotH / 2
        << ")\">average per-texel error</text>\n";
    for (const PlotPoint& p : points) {
        if (!(p.bytesPerTexel > 0) || !std::isfinite(p.error)) continue;
        const double x = px(p.bytesPerTexel), y = py(p.error);
        svg << "<circle cx=\"" << x << "\" cy=\"" << y << "\" r=\"5\" fill=\"#2a6fb0\"/>\n"
            << "<text x=\"" << x + 8 << "\" y=\"" << y - 6 << "\">" << escapeXml(p.label)
            << "</text>\n";
    }
    svg << "</svg>\n";
    return svg.str();
}

}  // namespace osgBTF
