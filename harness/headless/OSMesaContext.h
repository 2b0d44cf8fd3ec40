// osgBTF: the OSMesa back end of the headless context. Only in the static library osgBTF_osmesa,
// never in libosgBTF: a program that links it must put PkgConfig::OSMesa before every OSG or
// OpenGL library on its link line, and must never be run on a GPU (docs/headless.md 2.3).
#pragma once

#include "harness/headless/HeadlessContext.h"

namespace osgBTF {

/** Makes createHeadlessContext(HeadlessBackend::OSMesa, ...) and OSGBTF_HEADLESS=osmesa work in
 *  this program. Idempotent. (osgBTF_osmesa also calls it from a static initializer, but a static
 *  library's object file is only linked in when something references it, so call it.) */
void registerOSMesaBackend();

/** The OSMesa factory itself: an OSMESA_RGBA compatibility-profile context with depth 24 and
 *  stencil 8, and OSG's extension pointers redirected to OSMesaGetProcAddress (headless.md 2.3
 *  Rule 2). Throws osgBTF::Error when OSMesa cannot create the context or GL does not reach it. */
osg::ref_ptr<HeadlessContext> createOSMesaContext(int width, int height);

}  // namespace osgBTF
