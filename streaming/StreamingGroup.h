// osgBTF BSVTF in a scene (Schwartz et al. 2013 section 3): a Group above the MaterialNodes of
// streamed materials. Each frame it renders the feedback pass over its children (a pre-render
// camera at 1 / feedbackScale of the viewport, sharing the view and projection, every program
// replaced by streaming/bsvtf_feedback.frag) and reads it back; in the update traversal it counts
// the feedback's votes and runs its TileStreamer's update with them, so tiles stream in as the
// camera moves. Materials from streamer()->open(location) go on MaterialNodes below it. The
// read-back is asynchronous (two pixel-pack buffers): the update uses the feedback of the frame
// before.
#pragma once

#include <mutex>

#include <osg/Camera>
#include <osg/Group>
#include <osg/Image>
#include <osg/Texture2D>

#include "streaming/TileStreamer.h"

namespace osgBTF {

class StreamingGroup : public osg::Group {
public:
    /** With a streamer of default options (a 4032^2 cache, 124 MiB). */
    StreamingGroup();
    explicit StreamingGroup(TileStreamer* streamer);
    StreamingGroup(const StreamingGroup& other,
                   const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY);
    META_Node(osgBTF, StreamingGroup)

        TileStreamer* streamer() const {
        return _streamer.get();
    }
    /** Replaces the streamer (null: one of default options); for a group whose materials are
     *  not shown yet (the serializer sets the cache size this way). */
    void setStreamer(TileStreamer* streamer);
    /** Screen pixels per feedback pixel along each axis (default 4: seed-notes' quarter
     *  resolution); 1 renders the feedback at full resolution. */
    void setFeedbackScale(int scale);
    int feedbackScale() const { return _feedbackScale; }

    /** The votes of the last feedback image read back (empty before the first). */
    TileVotes lastVotes() const;
    /** A copy of the last feedback image read back (RGBA8: tile x, tile y, level, material + 1),
     *  that of the frame before the last one drawn; null before the second frame. */
    osg::ref_ptr<osg::Image> lastFeedback() const;
    /** True when the last update used a new feedback image and the streamer settled with it
     *  (TileStreamer::settled): for a static camera, the picture has converged. */
    bool settled() const { return _updatedWithFeedback && _streamer->settled(); }
    /** Operations of the last update. */
    std::size_t lastOperations() const { return _lastOperations; }

    /** Counts the votes of a new feedback image and runs the streamer's update with them: what
     *  the group's update callback does every frame. */
    void update();

    void traverse(osg::NodeVisitor& nv) override;

protected:
    ~StreamingGroup() override = default;

private:
    friend struct FeedbackReadBack;
    void setUp();
    void cullFeedback(osg::NodeVisitor& nv);

    osg::ref_ptr<TileStreamer> _streamer;
    osg::ref_ptr<osg::Camera> _feedbackCamera;
    osg::ref_ptr<osg::Texture2D> _feedbackTexture;
    osg::ref_ptr<osg::Uniform> _scaleUniform;
    int _feedbackScale = 4;
    mutable std::mutex _feedbackMutex;
    osg::ref_ptr<osg::Image> _feedback;  ///< the last one read back (copied in the draw thread)
    bool _feedbackIsNew = false, _updatedWithFeedback = false;
    TileVotes _votes;
    std::size_t _lastOperations = 0;
};

}  // namespace osgBTF
