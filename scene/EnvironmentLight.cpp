#include "scene/EnvironmentLight.h"

#include <cmath>

#include <osg/Light>
#include <osg/LightSource>
#include <osg/Notify>
#include <osgDB/FileUtils>
#include <osgDB/InputStream>
#include <osgDB/ObjectWrapper>
#include <osgDB/OutputStream>
#include <osgDB/ReadFile>

#include "core/Error.h"

namespace osgBTF {

EnvironmentLight::EnvironmentLight(const EnvironmentLight& other, const osg::CopyOp& copyop)
    : osg::Object(other, copyop),
      _file(other._file),
      _error(other._error),
      _exposure(other._exposure),
      _rotation(other._rotation),
      _projectionWidth(other._projectionWidth),
      _map(other._map),
      _exposureUniform(new osg::Uniform("osgBTF_envExposure", other._exposure)) {}

void EnvironmentLight::setExposure(float exposure) {
    _exposure = exposure;
    _exposureUniform->set(exposure);
}

osg::ref_ptr<osg::Group> representativeLightSources(const EnvironmentLight& light, int count) {
    osg::ref_ptr<osg::Group> group = new osg::Group;
    group->setName("osgBTF environment lights");
    if (!light.hasMap()) return group;
    int n = 0;
    for (const RepresentativeLight& r : medianCutLights(light.map(), count)) {
        osg::ref_ptr<osg::Light> l = new osg::Light(n++);
        const glm::vec3 p = r.power * light.getExposure();
        l->setDiffuse(osg::Vec4(p.x, p.y, p.z, 1.0f));
        l->setPosition(osg::Vec4(r.direction.x, r.direction.y, r.direction.z, 0.0f));
        osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
        source->setLight(l);
        group->addChild(source);
    }
    return group;
}

EnvironmentMap EnvironmentLight::mapFromImage(const osg::Image& image, const std::string& name) {
    if (image.s() < 1 || image.t() < 1 || !image.data()) throw Error(name + ": empty image");
    if (image.r() != 1) throw Error(name + ": a 3D image is not a lat-long map");
    EnvironmentMap map;
    map.width = image.s();
    map.height = image.t();
    map.rgb.resize(std::size_t(map.width) * std::size_t(map.height) * 3);
    // getColor reads every pixel format OSG knows (float as is, integers normalised to [0, 1]).
    for (int r = 0; r < map.height; ++r)
        for (int c = 0; c < map.width; ++c) {
            const osg::Vec4 v = image.getColor(unsigned(c), unsigned(r));
            float* p = map.rgb.data() + (std::size_t(r) * std::size_t(map.width) + c) * 3;
            for (int ch = 0; ch < 3; ++ch) {
                if (!std::isfinite(v[ch]) || v[ch] < 0.0f)
                    throw Error(name + ": pixel (" + std::to_string(c) + ", " + std::to_string(r) +
                                ") is negative or not finite");
                p[ch] = v[ch];
            }
        }
    return map;
}

void EnvironmentLight::setFile(const std::string& file, const osgDB::Options* options) {
    _file = file;
    _error.clear();
    _map = EnvironmentMap();
    if (file.empty()) return;
    try {
        const std::string path = osgDB::findDataFile(file, options);
        if (path.empty()) throw Error(file + ": file not found");
        osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(path, options);
        if (!image) throw Error(file + ": no osgDB plugin could read it as an image");
        _map = mapFromImage(*image, file);
    } catch (const std::exception& e) {
        _error = e.what();
        OSG_WARN << "osgBTF::EnvironmentLight: " << _error << std::endl;
    }
}

void EnvironmentLight::setImage(const osg::Image& image) {
    _map = mapFromImage(image, image.getFileName().empty() ? "image" : image.getFileName());
    _file.clear();
    _error.clear();
}

void EnvironmentLight::setMap(EnvironmentMap map) {
    _map = std::move(map);
    _file.clear();
    _error.clear();
}

EnvironmentMap EnvironmentLight::map() const {
    EnvironmentMap m = _map;
    m.rotationDegrees = _rotation;
    return m;
}

EnvironmentMap EnvironmentLight::projectionMap() const {
    if (!hasMap())
        throw Error("osgBTF::EnvironmentLight: no map" +
                    (_error.empty() ? "" : " (" + _error + ")"));
    EnvironmentMap m = map();
    const int width = std::max(2, _projectionWidth);
    if (m.width > width && m.width % width == 0 && m.height % std::max(1, width / 2) == 0)
        return m.downsampled(width);
    return m;
}

}  // namespace osgBTF

namespace {

bool checkFile(const osgBTF::EnvironmentLight& light) {
    return !light.getFile().empty();
}

bool readFile(osgDB::InputStream& is, osgBTF::EnvironmentLight& light) {
    std::string file;
    is.readWrappedString(file);
    light.setFile(file, is.getOptions());
    return true;
}

bool writeFile(osgDB::OutputStream& os, const osgBTF::EnvironmentLight& light) {
    os.writeWrappedString(light.getFile());
    os << std::endl;
    return true;
}

}  // namespace

REGISTER_OBJECT_WRAPPER(osgBTF_EnvironmentLight, new osgBTF::EnvironmentLight,
                        osgBTF::EnvironmentLight, "osg::Object osgBTF::EnvironmentLight") {
    ADD_USER_SERIALIZER(File);
    ADD_FLOAT_SERIALIZER(Exposure, 1.0f);
    ADD_FLOAT_SERIALIZER(Rotation, 0.0f);
    ADD_INT_SERIALIZER(ProjectionWidth, 128);
}
