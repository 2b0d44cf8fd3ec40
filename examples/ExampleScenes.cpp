#include "examples/ExampleScenes.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include <osg/Light>
#include <osg/MatrixTransform>
#include <osg/ShapeDrawable>
#include <osgDB/FileNameUtils>
#include <osgDB/Registry>
#include <osgDB/WriteFile>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>
#include <osgText/Text>
#include <osgUtil/SmoothingVisitor>

#include "core/Error.h"
#include "environment/EnvironmentLitGroup.h"
#include "scene/MaterialNode.h"

namespace osgBTF::examples {
namespace {

const double kPi = osg::PI;

osg::ref_ptr<osg::Geometry> newGeometry(osg::Vec3Array* vertices, osg::Vec3Array* normals,
                                        osg::Vec2Array* texcoords,
                                        osg::DrawElementsUInt* triangles) {
    osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
    geometry->setVertexArray(vertices);
    geometry->setNormalArray(normals, osg::Array::BIND_PER_VERTEX);
    geometry->setTexCoordArray(0, texcoords, osg::Array::BIND_PER_VERTEX);
    geometry->addPrimitiveSet(triangles);
    geometry->setUseDisplayList(false);
    geometry->setUseVertexBufferObjects(true);
    return geometry;
}

/** Two triangles per cell of a (rows+1) x (columns+1) vertex grid stored row by row, starting
 *  at `first`; counter-clockwise when +column runs along the first edge of the front side. */
void addGridTriangles(osg::DrawElementsUInt& triangles, unsigned first, int rows, int columns) {
    const unsigned stride = unsigned(columns + 1);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < columns; ++c) {
            const unsigned a = first + unsigned(r) * stride + unsigned(c), b = a + 1,
                           d = a + stride + 1, e = a + stride;
            for (unsigned index : {a, b, d, a, d, e}) triangles.push_back(index);
        }
}

osg::ref_ptr<osg::Geode> geodeOf(osg::Geometry* geometry, const std::string& name) {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->setName(name);
    geode->addDrawable(geometry);
    return geode;
}

/** Catmull-Rom interpolation of r(h) through (h, r) points with increasing h. */
double catmullRom(const std::vector<osg::Vec2d>& points, double h) {
    const std::size_t last = points.size() - 1;
    std::size_t i = 0;
    while (i + 1 < last && h > points[i + 1].x()) ++i;
    const osg::Vec2d& p1 = points[i];
    const osg::Vec2d& p2 = points[i + 1];
    const osg::Vec2d& p0 = i == 0 ? p1 : points[i - 1];
    const osg::Vec2d& p3 = i + 2 > last ? p2 : points[i + 2];
    const double t = std::clamp((h - p1.x()) / (p2.x() - p1.x()), 0.0, 1.0);
    // Slopes in r per unit h, so unevenly spaced points stay smooth.
    const double m1 = (p2.y() - p0.y()) / (p2.x() - p0.x()) * (p2.x() - p1.x());
    const double m2 = (p3.y() - p1.y()) / (p3.x() - p1.x()) * (p2.x() - p1.x());
    const double t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * p1.y() + (t3 - 2 * t2 + t) * m1 + (-2 * t3 + 3 * t2) * p2.y() +
           (t3 - t2) * m2;
}

}  // namespace

osg::ref_ptr<osg::Geode> createSphereModel() {
    const int segments = 64, rings = 32;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texcoords = new osg::Vec2Array;
    for (int r = 0; r <= rings; ++r) {
        const double theta = kPi * r / rings;  // 0 at the south pole (-Z)
        for (int s = 0; s <= segments; ++s) {
            const double phi = 2 * kPi * s / segments;
            const osg::Vec3 n(float(std::sin(theta) * std::cos(phi)),
                              float(std::sin(theta) * std::sin(phi)), float(-std::cos(theta)));
            vertices->push_back(n);
            normals->push_back(n);
            // t spans half of s's range: the equator is 2 pi long, a meridian pi, so texels
            // stay square.
            texcoords->push_back(osg::Vec2(float(s) / segments, 0.5f * float(r) / rings));
        }
    }
    osg::ref_ptr<osg::DrawElementsUInt> triangles =
        new osg::DrawElementsUInt(osg::PrimitiveSet::TRIANGLES);
    addGridTriangles(*triangles, 0, rings, segments);
    return geodeOf(newGeometry(vertices.get(), normals.get(), texcoords.get(), triangles.get()),
                   "sphere");
}

osg::ref_ptr<osg::Geode> createClothModel(int resolution) {
    if (resolution < 4) throw Error("createClothModel: resolution must be at least 4");
    const double tableRadius = 0.6, bendRadius = 0.1, bendLength = 0.5 * kPi * bendRadius;
    const osg::Matrix tilt = osg::Matrix::rotate(osg::DegreesToRadians(25.0), osg::X_AXIS);
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texcoords = new osg::Vec2Array;
    for (int j = 0; j <= resolution; ++j)
        for (int i = 0; i <= resolution; ++i) {
            // (u, v): where the point lies on the flat cloth, which does not stretch: its
            // distance from the centre becomes the length along the draped surface.
            const double u = -1.0 + 2.0 * i / resolution, v = -1.0 + 2.0 * j / resolution;
            const double d = std::hypot(u, v), phi = std::atan2(v, u);
            double radial = d, z = 0;
            if (d > tableRadius) {
                const double s = d - tableRadius;
                if (s <= bendLength) {  // over the rounded table edge
                    radial = tableRadius + bendRadius * std::sin(s / bendRadius);
                    z = -bendRadius * (1 - std::cos(s / bendRadius));
                } else {  // hanging: flaring out a little, folds deepening toward the hem
                    const double t = s - bendLength;
                    radial = tableRadius + bendRadius + 0.15 * t + 0.16 * t * std::sin(9 * phi);
                    z = -bendRadius - 0.97 * t;
                }
            }
            const osg::Vec3d p(radial * std::cos(phi), radial * std::sin(phi), z);
            vertices->push_back(p * tilt);
            texcoords->push_back(osg::Vec2(float(i) / resolution, float(j) / resolution));
        }
    osg::ref_ptr<osg::DrawElementsUInt> triangles =
        new osg::DrawElementsUInt(osg::PrimitiveSet::TRIANGLES);
    addGridTriangles(*triangles, 0, resolution, resolution);
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array(vertices->size());
    osg::ref_ptr<osg::Geometry> geometry =
        newGeometry(vertices.get(), normals.get(), texcoords.get(), triangles.get());
    // Normals averaged from the triangles around each vertex (the fold shape has no simple
    // closed form after the bend).
    osgUtil::SmoothingVisitor::smooth(*geometry);
    return geodeOf(geometry.get(), "cloth");
}

osg::ref_ptr<osg::Geode> createVaseModel(int segments, int profileSamples) {
    if (segments < 8 || profileSamples < 16)
        throw Error("createVaseModel: too few segments or profile samples");
    const double height = 1.6, lipRadius = 0.02, innerBottom = 0.06;
    // Outer radius over relative height: foot, belly, neck, flared lip.
    const std::vector<osg::Vec2d> outline = {{0.00, 0.30}, {0.08, 0.36}, {0.30, 0.52}, {0.55, 0.46},
                                             {0.78, 0.24}, {0.92, 0.22}, {1.00, 0.30}};
    // The profile as (radius, z) points: up the outside, over the lip, down the inside.
    std::vector<osg::Vec2d> profile;
    const int wallSamples = profileSamples * 9 / 20, lipSamples = profileSamples / 10;
    for (int k = 0; k < wallSamples; ++k) {
        const double h = double(k) / wallSamples;
        profile.emplace_back(catmullRom(outline, h), h * height);
    }
    const double lipCentre = catmullRom(outline, 1.0) - lipRadius;
    for (int k = 0; k <= lipSamples; ++k) {
        const double angle = kPi * k / lipSamples;
        profile.emplace_back(lipCentre + lipRadius * std::cos(angle),
                             height + lipRadius * std::sin(angle));
    }
    for (int k = 1; k <= wallSamples; ++k) {
        const double h = 1.0 - (1.0 - innerBottom) * k / wallSamples;
        profile.emplace_back(catmullRom(outline, h) - 2 * lipRadius, h * height);
    }
    std::vector<double> arcLength(profile.size(), 0.0);
    for (std::size_t p = 1; p < profile.size(); ++p)
        arcLength[p] = arcLength[p - 1] + (profile[p] - profile[p - 1]).length();

    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texcoords = new osg::Vec2Array;
    const double texturePeriod = 2 * kPi * 0.45;  // t per unit length: square texels at the belly
    for (std::size_t p = 0; p < profile.size(); ++p) {
        const osg::Vec2d tangent =
            profile[std::min(p + 1, profile.size() - 1)] - profile[p == 0 ? 0 : p - 1];
        osg::Vec2d normal(tangent.y(), -tangent.x());  // outward going up, inward going down
        normal.normalize();
        for (int k = 0; k <= segments; ++k) {
            const double theta = 2 * kPi * k / segments;
            const double c = std::cos(theta), s = std::sin(theta);
            vertices->push_back(osg::Vec3(float(profile[p].x() * c), float(profile[p].x() * s),
                                          float(profile[p].y())));
            normals->push_back(
                osg::Vec3(float(normal.x() * c), float(normal.x() * s), float(normal.y())));
            texcoords->push_back(
                osg::Vec2(float(k) / segments, float(arcLength[p] / texturePeriod)));
        }
    }
    osg::ref_ptr<osg::DrawElementsUInt> triangles =
        new osg::DrawElementsUInt(osg::PrimitiveSet::TRIANGLES);
    addGridTriangles(*triangles, 0, int(profile.size()) - 1, segments);

    // Bottom discs: under the foot facing -Z, inside facing +Z.
    for (bool inside : {false, true}) {
        const float z = inside ? float(innerBottom * height) : 0.0f;
        const double radius = inside ? profile.back().x() : profile.front().x();
        const osg::Vec3 normal(0, 0, inside ? 1.0f : -1.0f);
        const unsigned centre = unsigned(vertices->size());
        vertices->push_back(osg::Vec3(0, 0, z));
        normals->push_back(normal);
        texcoords->push_back(osg::Vec2(0.5f, 0.5f));
        for (int k = 0; k <= segments; ++k) {
            const double theta = 2 * kPi * k / segments;
            const osg::Vec2 xy(float(radius * std::cos(theta)), float(radius * std::sin(theta)));
            vertices->push_back(osg::Vec3(xy, z));
            normals->push_back(normal);
            texcoords->push_back(osg::Vec2(0.5f, 0.5f) + xy / float(texturePeriod));
        }
        for (int k = 0; k < segments; ++k) {
            const unsigned a = centre + 1 + unsigned(k), b = a + 1;
            // Counter-clockwise seen from the side the normal points to.
            triangles->push_back(centre);
            triangles->push_back(inside ? a : b);
            triangles->push_back(inside ? b : a);
        }
    }
    return geodeOf(newGeometry(vertices.get(), normals.get(), texcoords.get(), triangles.get()),
                   "vase");
}

std::vector<osg::ref_ptr<osg::LightSource>> createTwoLights(float rowWidth) {
    osg::ref_ptr<osg::LightSource> key = new osg::LightSource;
    key->setName("key light (warm, directional)");
    key->getLight()->setLightNum(0);
    key->getLight()->setPosition(osg::Vec4(-0.5f, -1.0f, 0.9f, 0.0f));  // toward the light
    key->getLight()->setDiffuse(osg::Vec4(1.0f, 0.93f, 0.82f, 1.0f));
    key->getLight()->setSpecular(osg::Vec4(1.0f, 0.93f, 0.82f, 1.0f));
    key->getLight()->setAmbient(osg::Vec4(0.05f, 0.05f, 0.05f, 1.0f));

    osg::ref_ptr<osg::LightSource> fill = new osg::LightSource;
    fill->setName("fill light (cool, point)");
    fill->getLight()->setLightNum(1);
    // Close to the row: a point light's position is part of the scene's bound, which sets
    // the viewer's home distance.
    fill->getLight()->setPosition(osg::Vec4(0.5f * rowWidth + 0.8f, -1.6f, 0.8f, 1.0f));
    fill->getLight()->setDiffuse(osg::Vec4(0.35f, 0.45f, 0.65f, 1.0f));
    fill->getLight()->setSpecular(osg::Vec4(0.35f, 0.45f, 0.65f, 1.0f));
    fill->getLight()->setAmbient(osg::Vec4(0.0f, 0.0f, 0.0f, 1.0f));
    return {key, fill};
}

osg::ref_ptr<osg::Group> createSideBySideScene(osg::Node* model,
                                               const std::vector<SceneItem>& items, float spacing,
                                               float textureScale, const osgDB::Options* options) {
    if (!model) throw Error("createSideBySideScene: no model");
    if (items.empty()) throw Error("createSideBySideScene: no materials");
    osg::ref_ptr<osg::Group> root = new osg::Group;
    const float rowWidth = spacing * float(items.size() - 1);
    for (const osg::ref_ptr<osg::LightSource>& light : createTwoLights(rowWidth))
        root->addChild(light.get());

    const osg::BoundingSphere bound = model->getBound();
    for (std::size_t i = 0; i < items.size(); ++i) {
        osg::ref_ptr<MaterialNode> node = new MaterialNode;
        node->setName(items[i].label);
        node->setTextureScale(textureScale);
        if (!node->setMaterialFile(items[i].materialFile, options))
            fail(items[i].materialFile, node->getMaterialError());
        node->addChild(model);

        const osg::Vec3 offset(-0.5f * rowWidth + spacing * float(i), 0.0f, 0.0f);
        osg::ref_ptr<osg::MatrixTransform> place =
            new osg::MatrixTransform(osg::Matrix::translate(offset));
        place->setName(items[i].label);
        place->addChild(node.get());

        osg::ref_ptr<osgText::Text> label = new osgText::Text;
        label->setText(items[i].label);
        label->setCharacterSize(0.12f * spacing);
        label->setAxisAlignment(osgText::Text::SCREEN);
        label->setAlignment(osgText::Text::CENTER_TOP);
        label->setPosition(bound.center() - osg::Vec3(0, 0, bound.radius() * 1.05f));
        label->setColor(osg::Vec4(1, 1, 1, 1));
        osg::ref_ptr<osg::Geode> labelGeode = new osg::Geode;
        labelGeode->setName("label");
        labelGeode->addDrawable(label.get());
        place->addChild(labelGeode.get());
        root->addChild(place.get());
    }
    return root;
}

void writeNodeAtomically(const osg::Node& node, const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    // Same folder (so the rename is atomic), same extension (osgDB picks the writer by it).
    const fs::path temporary =
        target.parent_path() / ("." + target.stem().string() + ".tmp-" +
                                std::to_string(::getpid()) + target.extension().string());
    const osgDB::ReaderWriter::WriteResult result =
        osgDB::Registry::instance()->writeNode(node, temporary.string(), nullptr);
    if (!result.success()) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        fail(path, "cannot write the scene" + (result.message().empty()
                                                   ? std::string(" (no osgDB writer for '") +
                                                         target.extension().string() + "')"
                                                   : ": " + result.message()));
    }
    std::error_code error;
    fs::rename(temporary, target, error);
    if (error) {
        fs::remove(temporary, error);
        fail(path, "cannot rename the written scene into place: " + error.message());
    }
}

osg::ref_ptr<osg::Group> createShadowedClothScene(const std::string& materialFile,
                                                  float textureScale,
                                                  const osgDB::Options* options) {
    osg::ref_ptr<osgShadow::ShadowedScene> scene = new osgShadow::ShadowedScene;
    scene->setName("shadowed cloth");
    osg::ref_ptr<osgShadow::ShadowMap> technique = new osgShadow::ShadowMap;
    technique->setTextureSize(osg::Vec2s(2048, 2048));
    scene->setShadowTechnique(technique.get());

    // Fill first, key last: ShadowMap shadows the last light it meets.
    osg::ref_ptr<osg::LightSource> fill = new osg::LightSource;
    fill->setName("fill light (cool, directional, no shadows)");
    fill->getLight()->setLightNum(0);
    fill->getLight()->setPosition(osg::Vec4(0.8f, -0.9f, 0.5f, 0.0f));
    fill->getLight()->setDiffuse(osg::Vec4(0.25f, 0.3f, 0.42f, 1.0f));
    fill->getLight()->setAmbient(osg::Vec4(0.0f, 0.0f, 0.0f, 1.0f));
    osg::ref_ptr<osg::LightSource> key = new osg::LightSource;
    key->setName("key light (warm, directional, casts shadows)");
    key->getLight()->setLightNum(1);
    key->getLight()->setPosition(osg::Vec4(skySunDirection(), 0.0f));  // the sky's sun
    key->getLight()->setDiffuse(osg::Vec4(1.0f, 0.93f, 0.82f, 1.0f));
    key->getLight()->setAmbient(osg::Vec4(0.08f, 0.08f, 0.08f, 1.0f));
    scene->addChild(fill.get());
    scene->addChild(key.get());
    // The plain shapes are lit by OSG's fixed-function lighting (ShadowMap's shader only
    // fragments): both lights on for the whole scene, not only below their LightSources.
    fill->setStateSetModes(*scene->getOrCreateStateSet(), osg::StateAttribute::ON);
    key->setStateSetModes(*scene->getOrCreateStateSet(), osg::StateAttribute::ON);

    osg::ref_ptr<MaterialNode> cloth = new MaterialNode;
    cloth->setName("cloth");
    cloth->setTextureScale(textureScale);
    if (!cloth->setMaterialFile(materialFile, options))
        fail(materialFile, cloth->getMaterialError());
    cloth->addChild(createClothModel(56).get());  // tangents: added by the node
    scene->addChild(cloth.get());

    // The table under the cloth (its top hidden by it, 0.01 below the cloth's flat top: rays
    // that environment lighting casts from the cloth must not start inside the table) and the
    // floor the folds shadow. The cloth model is tilted 25 degrees about X; so are these.
    const osg::Matrix tilt = osg::Matrix::rotate(osg::DegreesToRadians(25.0), osg::X_AXIS);
    osg::ref_ptr<osg::MatrixTransform> furniture = new osg::MatrixTransform(tilt);
    osg::ref_ptr<osg::Geode> props = new osg::Geode;
    props->setName("table and floor");
    osg::ref_ptr<osg::ShapeDrawable> table =
        new osg::ShapeDrawable(new osg::Cylinder(osg::Vec3(0, 0, -0.56f), 0.58f, 1.1f));
    table->setColor(osg::Vec4(0.35f, 0.22f, 0.12f, 1.0f));
    osg::ref_ptr<osg::ShapeDrawable> floor =
        new osg::ShapeDrawable(new osg::Box(osg::Vec3(0, 0, -1.13f), 3.2f, 3.2f, 0.06f));
    floor->setColor(osg::Vec4(0.6f, 0.6f, 0.58f, 1.0f));
    props->addDrawable(table.get());
    props->addDrawable(floor.get());
    furniture->addChild(props.get());
    scene->addChild(furniture.get());
    return scene;
}

osg::Vec3 skySunDirection() {
    const double azimuth = osg::DegreesToRadians(210.0), elevation = osg::DegreesToRadians(35.0);
    return osg::Vec3(float(std::cos(elevation) * std::cos(azimuth)),
                     float(std::cos(elevation) * std::sin(azimuth)), float(std::sin(elevation)));
}

FloatImage createSkyEnvironment(int width, int height) {
    if (width < 8 || height < 4)
        throw Error("createSkyEnvironment: size must be at least 8 x 4, got " +
                    std::to_string(width) + " x " + std::to_string(height));
    FloatImage image(width, height, 3);
    image.channelNames = {"R", "G", "B"};
    const osg::Vec3d sun(skySunDirection());
    const osg::Vec3d zenith(0.18, 0.32, 0.75), horizon(0.75, 0.8, 0.9), ground(0.12, 0.1, 0.08);
    // The sun's disc: 0.53 degrees across, so at 512 x 256 (0.7 degrees per texel) it is one
    // bright texel plus its glow, which carries most of the sky's directional light.
    const double sunRadius = osg::DegreesToRadians(0.265), sunRadiance = 20000 * zenith.z();
    for (int y = 0; y < height; ++y) {
        const double elevation = osg::PI_2 - osg::PI * (y + 0.5) / height;
        for (int x = 0; x < width; ++x) {
            const double azimuth = 2 * osg::PI * (x + 0.5) / width;
            const osg::Vec3d d(std::cos(elevation) * std::cos(azimuth),
                               std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
            osg::Vec3d c;
            if (elevation >= 0) {
                // Haze: the horizon colour fades into the zenith's over the lower ~30 degrees.
                const double t = std::pow(1.0 - std::sin(elevation), 4.0);
                c = zenith * (1 - t) + horizon * t;
            } else {
                const double t = std::min(1.0, -std::sin(elevation) * 8.0);
                c = horizon * 0.4 * (1 - t) + ground * t;
            }
            const double angle = std::acos(std::clamp(d * sun, -1.0, 1.0));
            const double glow = 2.0 * std::exp(-angle / osg::DegreesToRadians(4.0)) +
                                0.4 * std::exp(-angle / osg::DegreesToRadians(25.0));
            c += osg::Vec3d(1.0, 0.85, 0.6) * glow;
            // The disc, area-weighted per texel so its total power does not depend on the size.
            const double texelSolidAngle =
                (2 * osg::PI / width) * (osg::PI / height) * std::max(std::cos(elevation), 1e-6);
            const double discSolidAngle = osg::PI * sunRadius * sunRadius;
            const double texelRadius = std::sqrt(texelSolidAngle / osg::PI);
            if (angle < std::max(sunRadius, texelRadius))
                c += osg::Vec3d(1.0, 0.95, 0.85) * sunRadiance *
                     std::min(1.0, discSolidAngle / texelSolidAngle);
            for (int k = 0; k < 3; ++k) image.at(x, y, k) = float(c[k]);
        }
    }
    return image;
}

osg::ref_ptr<osg::Group> createEnvironmentLitClothScene(const std::string& materialFile,
                                                        const std::string& environmentFile,
                                                        float textureScale,
                                                        const osgDB::Options* options) {
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setFile(environmentFile, options);
    if (!light->hasMap()) fail(environmentFile, light->getError());
    osg::ref_ptr<EnvironmentLitGroup> scene = new EnvironmentLitGroup;
    scene->setName("environment-lit cloth");
    scene->setLight(light.get());
    osg::ref_ptr<MaterialNode> cloth = new MaterialNode;
    cloth->setName("cloth");
    cloth->setTextureScale(textureScale);
    if (!cloth->setMaterialFile(materialFile, options))
        fail(materialFile, cloth->getMaterialError());
    cloth->addChild(createClothModel(56).get());
    scene->addChild(cloth.get());
    return scene;
}

}  // namespace osgBTF::examples
