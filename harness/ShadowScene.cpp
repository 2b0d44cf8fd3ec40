#include "harness/ShadowScene.h"

#include <cmath>

#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Light>
#include <osg/LightSource>
#include <osg/ShapeDrawable>
#include <osg/Texture2D>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>
#include <osgShadow/SoftShadowMap>
#include <osgShadow/ViewDependentShadowMap>

#include "core/Error.h"
#include "scene/MaterialNode.h"

namespace osgBTF {

const std::vector<std::string>& shadowTechniqueNames() {
    static const std::vector<std::string> names = {"none", "ShadowMap", "SoftShadowMap",
                                                   "ViewDependentShadowMap"};
    return names;
}

osg::ref_ptr<osgShadow::ShadowTechnique> makeShadowTechnique(const std::string& name) {
    if (name == "none") return nullptr;
    if (name == "ShadowMap") return new osgShadow::ShadowMap;
    if (name == "SoftShadowMap") return new osgShadow::SoftShadowMap;
    if (name == "ViewDependentShadowMap") return new osgShadow::ViewDependentShadowMap;
    throw Error("shadow technique '" + name +
                "': unknown (none, ShadowMap, SoftShadowMap, ViewDependentShadowMap)");
}

namespace {

/** The ground: a `size` square at z = 0 centred on the origin, normal +Z, texture coordinates
 *  0..`repeat`. */
osg::ref_ptr<osg::Geometry> groundQuad(float size, float repeat) {
    const float h = size / 2;
    osg::ref_ptr<osg::Geometry> quad = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    vertices->push_back(osg::Vec3(-h, -h, 0));
    vertices->push_back(osg::Vec3(h, -h, 0));
    vertices->push_back(osg::Vec3(h, h, 0));
    vertices->push_back(osg::Vec3(-h, h, 0));
    osg::ref_ptr<osg::Vec2Array> texCoords = new osg::Vec2Array;
    texCoords->push_back(osg::Vec2(0, 0));
    texCoords->push_back(osg::Vec2(repeat, 0));
    texCoords->push_back(osg::Vec2(repeat, repeat));
    texCoords->push_back(osg::Vec2(0, repeat));
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array(1);
    (*normals)[0] = osg::Vec3(0, 0, 1);
    osg::ref_ptr<osg::Vec4Array> colors = new osg::Vec4Array(1);
    (*colors)[0] = osg::Vec4(1, 1, 1, 1);
    quad->setVertexArray(vertices.get());
    quad->setTexCoordArray(0, texCoords.get());
    quad->setNormalArray(normals.get(), osg::Array::BIND_OVERALL);
    quad->setColorArray(colors.get(), osg::Array::BIND_OVERALL);
    quad->addPrimitiveSet(new osg::DrawArrays(GL_QUADS, 0, 4));
    return quad;
}

/** A 64 x 64 RGB checker of two browns, repeated: what a plain textured ground looks like. */
osg::ref_ptr<osg::Texture2D> checkerTexture() {
    osg::ref_ptr<osg::Image> image = new osg::Image;
    const int size = 64;
    image->allocateImage(size, size, 1, GL_RGB, GL_UNSIGNED_BYTE);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            unsigned char* p = image->data(x, y);
            const bool dark = ((x / 8) + (y / 8)) % 2 != 0;
            p[0] = dark ? 110 : 170;
            p[1] = dark ? 80 : 130;
            p[2] = dark ? 50 : 90;
        }
    osg::ref_ptr<osg::Texture2D> texture = new osg::Texture2D(image.get());
    texture->setWrap(osg::Texture::WRAP_S, osg::Texture::REPEAT);
    texture->setWrap(osg::Texture::WRAP_T, osg::Texture::REPEAT);
    return texture;
}

}  // namespace

ShadowScene makeShadowScene(Material* ground, const std::string& technique, float groundSize,
                            float textureRepeat) {
    ShadowScene scene;
    osg::ref_ptr<osgShadow::ShadowTechnique> shadowTechnique = makeShadowTechnique(technique);
    if (shadowTechnique) {
        osg::ref_ptr<osgShadow::ShadowedScene> shadowed = new osgShadow::ShadowedScene;
        shadowed->setShadowTechnique(shadowTechnique.get());
        scene.root = shadowed;
    } else {
        scene.root = new osg::Group;
    }

    // A directional light 35 degrees from the zenith: the box's shadow falls on the ground beside
    // it, inside the view.
    const double theta = osg::DegreesToRadians(35.0);
    osg::ref_ptr<osg::Light> light = new osg::Light(0);
    light->setPosition(osg::Vec4(float(std::sin(theta)), 0.3f, float(std::cos(theta)), 0.0f));
    light->setDiffuse(osg::Vec4(1, 1, 1, 1));
    light->setAmbient(osg::Vec4(0.2f, 0.2f, 0.2f, 1));
    osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
    source->setLight(light.get());
    scene.root->addChild(source.get());

    osg::ref_ptr<osg::Geode> quad = new osg::Geode;
    scene.groundGeometry = groundQuad(groundSize, ground ? 1.0f : textureRepeat);
    quad->addDrawable(scene.groundGeometry.get());
    if (ground) {
        osg::ref_ptr<MaterialNode> node = new MaterialNode(ground);
        node->setTextureScale(textureRepeat);
        node->addChild(quad.get());
        scene.ground = node;
    } else {
        quad->getOrCreateStateSet()->setTextureAttributeAndModes(0, checkerTexture().get(),
                                                                 osg::StateAttribute::ON);
        scene.ground = quad;
    }
    scene.root->addChild(scene.ground.get());

    osg::ref_ptr<osg::Geode> box = new osg::Geode;
    box->addDrawable(new osg::ShapeDrawable(new osg::Box(osg::Vec3(0, 0, 1), 1.0f)));
    scene.box = box;
    scene.root->addChild(box.get());
    return scene;
}

CameraSetup shadowSceneCamera(int width, int height) {
    CameraSetup setup;
    setup.view =
        osg::Matrixd::lookAt(osg::Vec3d(0, -8, 6), osg::Vec3d(0, 0, 0.5), osg::Vec3d(0, 0, 1));
    setup.projection = osg::Matrixd::perspective(45.0, double(width) / double(height), 0.5, 50.0);
    setup.width = width;
    setup.height = height;
    return setup;
}

}  // namespace osgBTF
