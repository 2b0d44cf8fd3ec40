// osgBTF::EnvironmentLight: an HDR environment (lat-long map) that lights BTF materials (Sattler et
// al. 2003 section 5; the math is in materials/EnvironmentLighting.h).
//
// The map is read through osgDB: Radiance .hdr with OSG's own hdr plugin, OpenEXR with the
// project's osgdb_btfexr. Lat-long convention (EnvironmentMap): +Z up, the image's top row is the
// zenith, columns run in azimuth from +X toward +Y. Exposure scales the result at render time;
// the rotation (degrees about +Z) and the file change the projected per-vertex data.
//
// Serialized (.osgt/.osgb) as osgBTF::EnvironmentLight: File, Exposure, Rotation,
// ProjectionWidth.
#pragma once

#include <string>

#include <osg/Group>
#include <osg/Image>
#include <osg/Object>
#include <osg/Uniform>
#include <osg/ref_ptr>
#include <osgDB/Options>

#include "materials/EnvironmentLighting.h"

namespace osgBTF {

class EnvironmentLight : public osg::Object {
public:
    EnvironmentLight() = default;
    EnvironmentLight(const EnvironmentLight& other,
                     const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY);
    META_Object(osgBTF, EnvironmentLight)

        /** Reads the map through osgDB (found like any data file: as given, the options' database
         *  paths, OSG_FILE_PATH). A missing or unusable file: OSG_WARN "osgBTF::EnvironmentLight:
         *  FILE: problem", getError() holds the problem, the file name is kept and the environment
         *  is dark (no map). */
        void setFile(const std::string& file, const osgDB::Options* options = nullptr);
    const std::string& getFile() const { return _file; }
    /** An in-memory map (RGB or RGBA, float or 8-bit); clears the file name. Throws Error for an
     *  image that cannot be a map. */
    void setImage(const osg::Image& image);
    void setMap(EnvironmentMap map);

    void setExposure(float exposure);
    float getExposure() const { return _exposure; }
    /** osgBTF_envExposure, shared by every StateSet applyEnvironmentLighting makes (so a new
     *  exposure shows in the next frame, nothing recomputed). */
    osg::Uniform* getExposureUniform() const { return _exposureUniform.get(); }
    /** Degrees about +Z, counter-clockwise seen from above. */
    void setRotation(float degrees) { _rotation = degrees; }
    float getRotation() const { return _rotation; }
    /** Columns of the map the per-vertex projection runs over (the map is averaged down to it;
     *  cost per vertex ~ width^2 / 2). Default 128. */
    void setProjectionWidth(int width) { _projectionWidth = width; }
    int getProjectionWidth() const { return _projectionWidth; }

    const std::string& getError() const { return _error; }
    bool hasMap() const { return _map.width > 0; }
    int getMapWidth() const { return _map.width; }
    int getMapHeight() const { return _map.height; }
    /** The full-resolution map with this light's rotation. */
    EnvironmentMap map() const;
    /** The map the projection uses: rotated and averaged down to the projection width (a map of
     *  a size that does not divide evenly stays at full size). Throws Error without a map. */
    EnvironmentMap projectionMap() const;

    /** Converts an osg::Image (rows bottom-up) into a map; throws Error "NAME: problem". */
    static EnvironmentMap mapFromImage(const osg::Image& image, const std::string& name);

protected:
    ~EnvironmentLight() override = default;

private:
    std::string _file, _error;
    float _exposure = 1.0f, _rotation = 0.0f;
    int _projectionWidth = 128;
    EnvironmentMap _map;
    osg::ref_ptr<osg::Uniform> _exposureUniform = new osg::Uniform("osgBTF_envExposure", 1.0f);
};

/** Directional osg::LightSources for representative lights (medianCutLights of the light's
 *  rotated map; diffuse = power x exposure, position = the direction toward the light, w = 0):
 *  MaterialNode feeds them to any method's point-light shader (at most 8 lights there). */
osg::ref_ptr<osg::Group> representativeLightSources(const EnvironmentLight& light, int count = 8);

}  // namespace osgBTF
