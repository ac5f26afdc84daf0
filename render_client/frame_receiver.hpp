// What the render client sends and receives on its links (NodeLinks) and how it verifies it
// (paper 4.5): the cameras, the resyncs that start everyone over, and each frame's camera, diff
// and EndOfFrame from the node doing HC, checked against what this client computes itself
// (camera order, the diff stream, the front hash).
#pragma once
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <vector>

#include "common/camera.hpp"
#include "protocol/visible_set.hpp"
#include "protocol/wire.hpp"
#include "render_client/node_links.hpp"

namespace occ {

class SwitchStep;

class FrameReceiver {
 public:
  using Clock = std::chrono::steady_clock;
  // `path`: the cameras (it may grow: --window).
  FrameReceiver(const ClientOptions& o, NodeLinks& links, const std::vector<Camera>& path)
      : o_(o), links_(links), path_(path) {}

  // Camera `number` (the next one: cameras_sent()) to every node that is up, with Camera.occlusion
  // `occlusion` (also for resends); a node that cannot take it is dropped.
  void send_camera(uint32_t number, uint8_t occlusion);
  uint32_t cameras_sent() const { return uint32_t(occlusion_.size()); }
  Clock::time_point sent_at(uint32_t camera) const { return sent_at_.at(camera); }

  // Before frame `frame`: while a node was dropped or came back, everyone starts over at it with
  // empty sets (wire.hpp Resync), `visible` cleared.
  void resync_if_needed(uint32_t frame, VisibleSet& visible);
  bool resynced_at(uint32_t frame) const { return resync_frame_ == frame; }
  uint32_t resyncs() const { return resyncs_; }

  // Frame `frame` from switch node k: its camera, the diff, EndOfFrame; `visible` becomes V_f.
  // Null when the node failed meanwhile (it is dropped).
  struct Served {
    wire::Camera wcam;
    wire::EndOfFrame eof;
    uint64_t bytes = 0;
    uint64_t diff_bytes = 0;  // of them, the NodeDiff messages'
  };
  std::optional<Served> receive(int k, uint32_t frame, VisibleSet& visible, const SwitchStep& step);
  // The camera frame `frame` used (cameras strictly increase).
  void used_camera(uint32_t camera) { prev_camera_ = camera; }

 private:
  void send_camera_to(int k, uint32_t number);
  void resync(uint32_t frame, VisibleSet& visible);
  net::Received skip_stale(int k, uint32_t frame);
  void check_camera(int k, uint32_t frame, const wire::Camera& wcam) const;
  Served receive_frame(int k, uint32_t frame, VisibleSet& visible, const SwitchStep& step);
  NodeFault fault(int k, uint32_t frame, const std::string& what) const;

  const ClientOptions& o_;
  NodeLinks& links_;
  const std::vector<Camera>& path_;
  std::map<uint32_t, Clock::time_point> sent_at_;
  std::vector<uint8_t> occlusion_;  // per camera sent: Camera.occlusion (0: the frustum set)
  DiffReceiver streams_[2];
  uint32_t epoch_ = 0, resyncs_ = 0;
  uint32_t frame_ = 0;                    // the frame being received (for messages)
  std::optional<uint32_t> resync_frame_;  // the frame of the last resync
  std::optional<uint32_t> prev_camera_;   // the camera of the previous frame
};

}  // namespace occ
