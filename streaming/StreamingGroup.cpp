#include "streaming/StreamingGroup.h"

#include <cmath>
#include <cstring>
#include <map>
#include <mutex>

#include <osg/BufferObject>
#include <osg/GLExtensions>
#include <osg/State>
#include <osg/Texture2D>

#include <osg/Viewport>
#include <osgUtil/CullVisitor>

#include "core/Error.h"
#include "materials/Material.h"
#include "materials/MethodPrograms.h"

namespace osgBTF {

namespace {

/** Renders the group's children (not the group: that would recurse into the feedback camera). */
struct ChildrenOf : osg::Node {
    explicit ChildrenOf(StreamingGroup* group) : _group(group) {}
    void traverse(osg::NodeVisitor& nv) override {
        osg::ref_ptr<StreamingGroup> group;
        if (_group.lock(group)) group->osg::Group::traverse(nv);
    }
    osg::BoundingSphere computeBound() const override {
        osg::ref_ptr<StreamingGroup> group;
        return _group.lock(group) ? group->osg::Group::computeBound() : osg::BoundingSphere();
    }
    osg::observer_ptr<StreamingGroup> _group;
};

struct UpdateStreaming : osg::NodeCallback {
    void operator()(osg::Node* node, osg::NodeVisitor* nv) override;
};

}  // namespace

/** Reads the feedback pass back without waiting for it (Schwartz et al. 2013: the feedback is "read
 * back asynchronously"): after the pass, glGetTexImage of its texture into one of two pixel-pack
 *  buffers, and a map of the other one, which the pass of the previous frame filled. The GPU
 *  copies while the frame goes on; the update sees feedback one frame old. Draw thread of each
 *  context that draws the group, with buffers of its own (the update takes the latest image
 *  any of them read). */
struct FeedbackReadBack : osg::Camera::DrawCallback {
    explicit FeedbackReadBack(StreamingGroup* group) : _group(group) {}
    void operator()(osg::RenderInfo& renderInfo) const override {
        osg::ref_ptr<StreamingGroup> group;
        if (!_group.lock(group)) return;
        osg::State& state = *renderInfo.getState();
        osg::GLExtensions* ext = state.get<osg::GLExtensions>();
        osg::Texture2D* texture = group->_feedbackTexture.get();
        if (!ext || !ext->isBufferObjectSupported ||
            !texture->getTextureObject(state.getContextID()))
            return;
        // Buffers are objects of one context: each context that draws the group has its own.
        PerContext& c = [&]() -> PerContext& {
            std::lock_guard<std::mutex> lock(_contextsMutex);
            return _contexts[state.getContextID()];
        }();
        if (!c.buffers[0]) ext->glGenBuffers(2, c.buffers);
        const int w = texture->getTextureWidth(), h = texture->getTextureHeight();
        const GLsizeiptr bytes = GLsizeiptr(w) * h * 4;
        // Issue this frame's copy.
        Slot& issue = c.slots[c.next];
        ext->glBindBuffer(GL_PIXEL_PACK_BUFFER_ARB, c.buffers[c.next]);
        if (issue.bytes != bytes)
            ext->glBufferData(GL_PIXEL_PACK_BUFFER_ARB, bytes, nullptr, GL_STREAM_READ_ARB);
        state.applyTextureAttribute(0, texture);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        issue = {w, h, bytes, true};
        // Take the previous frame's.
        const int other = 1 - c.next;
        Slot& ready = c.slots[other];
        if (ready.pending) {
            ext->glBindBuffer(GL_PIXEL_PACK_BUFFER_ARB, c.buffers[other]);
            if (const void* data = ext->glMapBuffer(GL_PIXEL_PACK_BUFFER_ARB, GL_READ_ONLY_ARB)) {
                osg::ref_ptr<osg::Image> copy = new osg::Image;
                copy->allocateImage(ready.width, ready.height, 1, GL_RGBA, GL_UNSIGNED_BYTE);
                std::memcpy(copy->data(), data, std::size_t(ready.bytes));
                ext->glUnmapBuffer(GL_PIXEL_PACK_BUFFER_ARB);
                std::lock_guard<std::mutex> lock(group->_feedbackMutex);
                group->_feedback = copy;
                group->_feedbackIsNew = true;
            }
            ready.pending = false;
        }
        ext->glBindBuffer(GL_PIXEL_PACK_BUFFER_ARB, 0);
        c.next = other;
    }
    struct Slot {
        int width = 0, height = 0;
        GLsizeiptr bytes = 0;
        bool pending = false;
    };
    struct PerContext {
        GLuint buffers[2] = {0, 0};
        Slot slots[2];
        int next = 0;
    };
    osg::observer_ptr<StreamingGroup> _group;
    mutable std::mutex _contextsMutex;
    mutable std::map<unsigned, PerContext> _contexts;  ///< by context ID
};

namespace {
void UpdateStreaming::operator()(osg::Node* node, osg::NodeVisitor* nv) {
    static_cast<StreamingGroup*>(node)->update();
    traverse(node, nv);
}
}  // namespace

StreamingGroup::StreamingGroup() : StreamingGroup(new TileStreamer) {}

StreamingGroup::StreamingGroup(TileStreamer* streamer) : _streamer(streamer) {
    setUp();
}

StreamingGroup::StreamingGroup(const StreamingGroup& other, const osg::CopyOp& copyop)
    : osg::Group(other, copyop), _streamer(other._streamer), _feedbackScale(other._feedbackScale) {
    setUp();
}

void StreamingGroup::setStreamer(TileStreamer* streamer) {
    _streamer = streamer ? streamer : new TileStreamer;
    _votes = _streamer->makeVotes();
}

void StreamingGroup::setUp() {
    if (!_streamer) _streamer = new TileStreamer;
    _votes = _streamer->makeVotes();
    _feedbackTexture = new osg::Texture2D;
    _feedbackTexture->setTextureSize(1, 1);
    _feedbackTexture->setInternalFormat(GL_RGBA8);
    _feedbackTexture->setSourceFormat(GL_RGBA);
    _feedbackTexture->setSourceType(GL_UNSIGNED_BYTE);
    _feedbackTexture->setFilter(osg::Texture::MIN_FILTER, osg::Texture::NEAREST);
    _feedbackTexture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::NEAREST);
    _feedbackTexture->setResizeNonPowerOfTwoHint(false);
    _feedbackCamera = new osg::Camera;
    _feedbackCamera->setName("osgBTF BSVTF feedback");
    _feedbackCamera->setRenderOrder(osg::Camera::PRE_RENDER);
    // The view and projection of the camera that renders the group: the same picture, smaller.
    _feedbackCamera->setReferenceFrame(osg::Transform::RELATIVE_RF);
    _feedbackCamera->setRenderTargetImplementation(osg::Camera::FRAME_BUFFER_OBJECT);
    _feedbackCamera->setClearColor(osg::Vec4(0, 0, 0, 0));
    _feedbackCamera->setClearMask(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    _feedbackCamera->setViewport(0, 0, 1, 1);
    _feedbackCamera->attach(osg::Camera::COLOR_BUFFER, _feedbackTexture.get());
    _feedbackCamera->attach(osg::Camera::DEPTH_BUFFER, GL_DEPTH_COMPONENT24);
    _feedbackCamera->setPostDrawCallback(new FeedbackReadBack(this));
    osg::StateSet* state = _feedbackCamera->getOrCreateStateSet();
    state->setAttributeAndModes(methodProgram("bsvtf_feedback").get(),
                                osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
    state->setMode(GL_BLEND, osg::StateAttribute::OFF | osg::StateAttribute::OVERRIDE);
    // Streamed materials set their own id; everything else writes "no material".
    state->addUniform(new osg::Uniform("bsvtfMaterialId", -1));
    _scaleUniform = new osg::Uniform("bsvtfFeedbackScale", float(_feedbackScale));
    state->addUniform(_scaleUniform.get());
    _feedbackCamera->addChild(new ChildrenOf(this));
    setUpdateCallback(new UpdateStreaming);
}

void StreamingGroup::setFeedbackScale(int scale) {
    if (scale < 1)
        throw Error("StreamingGroup: the feedback scale must be >= 1, got " +
                    std::to_string(scale));
    _feedbackScale = scale;
    _scaleUniform->set(float(scale));
}

TileVotes StreamingGroup::lastVotes() const {
    return _votes;
}

osg::ref_ptr<osg::Image> StreamingGroup::lastFeedback() const {
    std::lock_guard<std::mutex> lock(_feedbackMutex);
    return _feedback ? new osg::Image(*_feedback, osg::CopyOp::DEEP_COPY_ALL) : nullptr;
}

void StreamingGroup::update() {
    osg::ref_ptr<osg::Image> feedback;
    {
        std::lock_guard<std::mutex> lock(_feedbackMutex);
        if (_feedbackIsNew) feedback = _feedback;
        _feedbackIsNew = false;
    }
    if (_votes.materialCount() != _streamer->materialCount()) _votes = _streamer->makeVotes();
    if (feedback) {
        // Schwartz et al. 2013 eq. 9: every pixel votes for its tile (and so its ancestors).
        _votes.clear();
        const unsigned char* p = feedback->data();
        const std::size_t pixels = std::size_t(feedback->s()) * std::size_t(feedback->t());
        for (std::size_t i = 0; i < pixels; ++i, p += 4)
            if (p[3] > 0) _votes.add(int(p[3]) - 1, int(p[2]), int(p[0]), int(p[1]));
    }
    _lastOperations = _streamer->update(_votes);
    _updatedWithFeedback = bool(feedback);
}

void StreamingGroup::cullFeedback(osg::NodeVisitor& nv) {
    auto* cv = nv.asCullVisitor();
    const osg::Viewport* viewport = cv ? cv->getViewport() : nullptr;
    if (!viewport) return;
    const int w = std::max(1, int(std::ceil(viewport->width() / _feedbackScale)));
    const int h = std::max(1, int(std::ceil(viewport->height() / _feedbackScale)));
    if (_feedbackTexture->getTextureWidth() != w || _feedbackTexture->getTextureHeight() != h) {
        _feedbackTexture->setTextureSize(w, h);
        _feedbackTexture->dirtyTextureObject();
        _feedbackCamera->setViewport(0, 0, w, h);
        _feedbackCamera->dirtyAttachmentMap();
    }
    _feedbackCamera->accept(nv);
}

void StreamingGroup::traverse(osg::NodeVisitor& nv) {
    if (nv.getVisitorType() == osg::NodeVisitor::CULL_VISITOR) cullFeedback(nv);
    osg::Group::traverse(nv);
}

}  // namespace osgBTF
