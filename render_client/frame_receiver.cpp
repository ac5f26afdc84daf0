#include "render_client/frame_receiver.hpp"

#include <iostream>

#include "common/hash.hpp"
#include "protocol/cluster/switch_step.hpp"

namespace occ {

void FrameReceiver::send_camera(uint32_t number, uint8_t occlusion) {
  sent_at_[number] = Clock::now();
  if (occlusion_.size() <= number) occlusion_.resize(number + 1, 1);
  occlusion_[number] = occlusion;  // the same for both nodes and for resends
  for (int k = 0; k < 2; ++k)
    if (links_.up(k)) send_camera_to(k, number);
}

void FrameReceiver::send_camera_to(int k, uint32_t number) {
  const wire::Camera w = to_wire(number, path_[number], {o_.width, o_.height}, occlusion_.at(number));
  if (auto err = links_.conn(k).send(w))
    links_.drop(k, "frame " + std::to_string(frame_) + ": sending camera " + std::to_string(number) + " to " +
                       links_.node_name(k) + ": " + *err);
}

void FrameReceiver::resync_if_needed(uint32_t frame, VisibleSet& visible) {
  frame_ = frame;
  links_.take_rejoined(frame);
  while (links_.resync_needed()) resync(frame, visible);
}

// Everyone starts over at `frame` with empty sets: the switch if both nodes are up, the one that
// is up alone, or nobody (frustum culling here). Nodes that fail to take it are dropped, and the
// caller calls again.
void FrameReceiver::resync(uint32_t frame, VisibleSet& visible) {
  links_.resync_started();
  visible.clear();
  for (auto& s : streams_) s = DiffReceiver{};
  resync_frame_.reset();
  const int n = links_.members();
  if (n == 0) {
    std::cerr << "render_client: frame " << frame << ": no switch node: frustum culling in the render client\n";
    return;
  }
  if (!links_.is_switch()) return;  // an occlusion_server is never resynchronised (its failure leaves frustum culling)
  ++epoch_;
  for (int k = 0; k < 2; ++k) {
    if (!links_.up(k)) continue;
    links_.await_epoch(k) = epoch_;
    if (auto err = links_.conn(k).send(wire::Resync{frame, epoch_, uint32_t(n)})) {
      links_.drop(k, "frame " + std::to_string(frame) + ": sending the resync to " + links_.node_name(k) + ": " + *err);
      return;
    }
    // The cameras it may lack (a restarted node has none; the other may have used them).
    const uint32_t sent = cameras_sent();
    if (o_.config.camera_mode == CameraMode::lockstep) {
      for (uint32_t c = frame; c < sent && links_.up(k); ++c) send_camera_to(k, c);
    } else if (sent > 0) {
      send_camera_to(k, sent - 1);
    }
    if (!links_.up(k)) return;  // dropped: a resync is needed again
  }
  resync_frame_ = frame;
  ++resyncs_;
  std::cerr << "render_client: frame " << frame << ": resync " << epoch_ << ": "
            << (n == 2 ? std::string("the switch resumes (switch nodes 0 and 1)")
                       : links_.node_name(links_.server_of(frame)) + " serves alone")
            << ", from a full visible set\n";
}

std::optional<FrameReceiver::Served> FrameReceiver::receive(int k, uint32_t frame, VisibleSet& visible,
                                                            const SwitchStep& step) {
  try {
    return receive_frame(k, frame, visible, step);
  } catch (const NodeFault& e) {
    links_.drop(e.node, e.what());
  }
  return std::nullopt;
}

NodeFault FrameReceiver::fault(int k, uint32_t frame, const std::string& what) const {
  return NodeFault(k, "frame " + std::to_string(frame) + ": " + links_.node_name(k) + " " + what);
}

// The first message of frame `frame` from node k: what it sent before acknowledging the last
// resync is stale.
net::Received FrameReceiver::skip_stale(int k, uint32_t frame) {
  net::Received r = links_.receive_from(k, frame);
  while (links_.await_epoch(k)) {
    if (auto* rs = std::get_if<wire::Resync>(&r.message); rs && rs->epoch == links_.await_epoch(k)) {
      if (!resync_frame_ || rs->frame != *resync_frame_ || rs->nodes != uint32_t(links_.members()))
        throw fault(k, frame,
                    "acknowledged resync " + std::to_string(rs->epoch) + " for frame " + std::to_string(rs->frame) +
                        " with " + std::to_string(rs->nodes) + " nodes");
      links_.await_epoch(k) = 0;
    }
    r = links_.receive_from(k, frame);
  }
  return r;
}

// The camera HC used for frame `frame`: one this client sent, newer than the previous frame's
// (lockstep: camera `frame`), for this viewport.
void FrameReceiver::check_camera(int k, uint32_t frame, const wire::Camera& wcam) const {
  if (wcam.frame >= path_.size() || !sent_at_.count(wcam.frame))
    throw fault(k, frame, "used camera " + std::to_string(wcam.frame) + " that was never sent");
  if (o_.config.camera_mode == CameraMode::lockstep && wcam.frame != frame)
    throw fault(k, frame, "used camera " + std::to_string(wcam.frame) + " (lockstep)");
  if (prev_camera_ && wcam.frame <= *prev_camera_)
    throw fault(k, frame,
                "used camera " + std::to_string(wcam.frame) + ", not newer than frame " + std::to_string(frame - 1) +
                    "'s camera " + std::to_string(*prev_camera_));
  if (auto err = viewport_mismatch(wcam, {o_.width, o_.height})) throw fault(k, frame, "sent " + *err);
}

// Throws NodeFault.
FrameReceiver::Served FrameReceiver::receive_frame(int k, uint32_t frame, VisibleSet& visible, const SwitchStep& step) {
  // 0. Stale messages; 1. the camera HC used for this frame comes first.
  net::Received r = skip_stale(k, frame);
  auto* wcam = std::get_if<wire::Camera>(&r.message);
  if (!wcam)
    throw fault(k, frame, "sent " + std::string(wire::type_name(wire::type_of(r.message))) + " before the camera");
  check_camera(k, frame, *wcam);
  Served s{*wcam, {}, r.wire_bytes};  // this frame's messages only (the io thread may read ahead)
  // Front tracking (switch_step.hpp): coarsen V_{f-1} for camera f exactly as the switch
  // nodes do; the diff is relative to the result, whose hash EndOfFrame.front_hash carries.
  const uint64_t expected_front = step.coarsen(visible, from_wire(*wcam));
  // 2. Diff chunks, then EndOfFrame.
  for (;;) {
    net::Received m = links_.receive_from(k, frame);
    s.bytes += m.wire_bytes;
    if (std::holds_alternative<wire::NodeDiff>(m.message)) s.diff_bytes += m.wire_bytes;
    if (auto* d = std::get_if<wire::NodeDiff>(&m.message)) {
      if (auto err = streams_[k].on_diff(visible, *d)) throw fault(k, frame, "desync: " + *err);
    } else if (auto* e = std::get_if<wire::EndOfFrame>(&m.message)) {
      if (e->frame != frame) throw fault(k, frame, "ended frame " + std::to_string(e->frame));
      if (auto err = streams_[k].on_end_of_frame(visible, *e)) throw fault(k, frame, "desync: " + *err);
      if (e->front_hash != expected_front)
        throw fault(k, frame,
                    "desync: front hash " + hex(e->front_hash) + " from the node, " + hex(expected_front) + " here");
      s.eof = *e;
      return s;
    } else {
      throw fault(k, frame, "sent an unexpected " + std::string(wire::type_name(wire::type_of(m.message))));
    }
  }
}

}  // namespace occ
