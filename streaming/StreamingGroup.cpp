#include "streaming/StreamingGroup.h"

#include <cmath>

#include <osg/Viewport>
#include <osgUtil/CullVisitor>

#include "core/Error.h"
#include "materials/Material.h"

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

/** Copies the feedback image after the pass drew and read it back (draw thread). */
struct FeedbackReadBack : osg::Camera::DrawCallback {
    explicit FeedbackReadBack(StreamingGroup* group) : _group(group) {}
    void operator()(osg::RenderInfo&) const override {
        osg::ref_ptr<StreamingGroup> group;
        if (!_group.lock(group)) return;
        osg::ref_ptr<osg::Image> copy =
            new osg::Image(*group->_feedbackTarget, osg::CopyOp::DEEP_COPY_ALL);
        std::lock_guard<std::mutex> lock(group->_feedbackMutex);
        group->_feedback = copy;
        group->_feedbackIsNew = true;
    }
    osg::observer_ptr<StreamingGroup> _group;
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

void StreamingGroup::setUp() {
    if (!_streamer) _streamer = new TileStreamer;
    _votes = _streamer->makeVotes();
    _feedbackTarget = new osg::Image;
    _feedbackTarget->allocateImage(1, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE);
    _feedbackCamera = new osg::Camera;
    _feedbackCamera->setName("osgBTF BSVTF feedback");
    _feedbackCamera->setRenderOrder(osg::Camera::PRE_RENDER);
    // The view and projection of the camera that renders the group: the same picture, smaller.
    _feedbackCamera->setReferenceFrame(osg::Transform::RELATIVE_RF);
    _feedbackCamera->setRenderTargetImplementation(osg::Camera::FRAME_BUFFER_OBJECT);
    _feedbackCamera->setClearColor(osg::Vec4(0, 0, 0, 0));
    _feedbackCamera->setClearMask(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    _feedbackCamera->setViewport(0, 0, 1, 1);
    _feedbackCamera->attach(osg::Camera::COLOR_BUFFER, _feedbackTarget.get());
    _feedbackCamera->attach(osg::Camera::DEPTH_BUFFER, GL_DEPTH_COMPONENT24);
    _feedbackCamera->setFinalDrawCallback(new FeedbackReadBack(this));
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
        // Seed 003 eq. 9: every pixel votes for its tile (and so its ancestors).
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
    if (_feedbackTarget->s() != w || _feedbackTarget->t() != h) {
        _feedbackTarget->allocateImage(w, h, 1, GL_RGBA, GL_UNSIGNED_BYTE);
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
