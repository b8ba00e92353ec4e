// The uploaded real-time move (see rt_move.h).
#include "devices/dmc16/rt_move.h"

namespace moco::devices {

using dmc::AckCode;

RtMove::RtMove(uint32_t max_frames, int motor_count, int dmx_channels)
    : max_frames_(max_frames), motor_count_(motor_count), dmx_channels_(dmx_channels) {}

void RtMove::Clear() {
  in_progress_ = false;
  complete_ = false;
  start_ = end_ = frames_ = 0;
  axes_.clear();
  dmx_.clear();
  trigger_mask_ = 0;
  triggers_.clear();
}

UploadResult RtMove::Begin(uint32_t start_frame, uint32_t end_frame) {
  Clear();
  if (end_frame < start_frame) {
    return {AckCode::kErrRange, "END FRAME is before START FRAME"};
  }
  const uint64_t n = uint64_t{end_frame} - start_frame + 1;
  if (n > max_frames_) {
    return {AckCode::kErrRange, std::to_string(n) + " frames exceed the upload frame count " +
                                    std::to_string(max_frames_)};
  }
  in_progress_ = true;
  start_ = start_frame;
  end_ = end_frame;
  frames_ = static_cast<uint32_t>(n);
  return {};
}

template <typename T>
UploadResult RtMove::Store(std::map<int, Track<T>>& tracks, int key, uint32_t start_index,
                           bool last_set, const std::vector<T>& values) {
  const uint64_t stop = uint64_t{start_index} + values.size();
  if (values.empty() || stop > frames_) {
    return {AckCode::kErrRange, "indices " + std::to_string(start_index) + ".." +
                                    std::to_string(stop == 0 ? 0 : stop - 1) + " outside the " +
                                    std::to_string(frames_) + " frames of the upload"};
  }
  Track<T>& track = tracks[key];  // created only for a section that is stored
  if (track.values.empty()) {
    track.values.assign(frames_, T{});
    track.have.assign(frames_, false);
  }
  for (size_t i = 0; i < values.size(); ++i) {
    track.values[start_index + i] = values[i];
    track.have[start_index + i] = true;
  }
  if (last_set) {
    track.last_set = true;
    track.repeat_from = static_cast<uint32_t>(stop);
  }
  return {};
}

UploadResult RtMove::Axis(const dmc::RtUploadMoveAxis& m) {
  if (!in_progress_)
    return {AckCode::kErrGeneral, "no upload in progress (send UPLOAD_MOVE_BEGIN)"};
  if (m.motor < 1 || m.motor > motor_count_) {
    return {AckCode::kErrRange, "motor " + std::to_string(m.motor) + " does not exist"};
  }
  return Store(axes_, m.motor, m.start_index, m.last_set, m.positions_steps);
}

UploadResult RtMove::Dmx(const dmc::RtUploadMoveDmx& m) {
  if (!in_progress_)
    return {AckCode::kErrGeneral, "no upload in progress (send UPLOAD_MOVE_BEGIN)"};
  if (m.channel < 1 || m.channel > dmx_channels_) {
    return {AckCode::kErrRange, "DMX channel " + std::to_string(m.channel) + " does not exist"};
  }
  return Store(dmx_, m.channel, m.start_index, m.last_set, m.levels);
}

UploadResult RtMove::Triggers(const dmc::RtUploadMoveTriggers& m) {
  if (!in_progress_)
    return {AckCode::kErrGeneral, "no upload in progress (send UPLOAD_MOVE_BEGIN)"};
  for (const dmc::TriggerPoint& p : m.points) {
    if (p.frame_index >= frames_ && trigger_frames_checked_) {
      return {AckCode::kErrRange,
              "trigger frame index " + std::to_string(p.frame_index) + " outside the upload"};
    }
  }
  // "Should be the same every time": a differing mask is merged, not refused.
  trigger_mask_ |= m.mask;
  for (const dmc::TriggerPoint& p : m.points) {
    // Unchecked (dmc-lite), a point past the range names no frame: dropped.
    if (p.frame_index < frames_) triggers_[p.frame_index] = p.values & m.mask;
  }
  return {};
}

template <typename T>
bool RtMove::Covered(const Track<T>& track) const {
  const uint32_t filled_to = track.last_set ? track.repeat_from : frames_;
  for (uint32_t i = 0; i < filled_to; ++i) {
    if (!track.have[i]) return false;
  }
  return true;
}

template <typename T>
void RtMove::Finalize(Track<T>& track) const {
  if (track.last_set && track.repeat_from > 0) {
    for (uint32_t i = track.repeat_from; i < frames_; ++i) {
      track.values[i] = track.values[track.repeat_from - 1];
    }
  }
  track.have.clear();
  track.have.shrink_to_fit();
}

UploadResult RtMove::End() {
  if (!in_progress_)
    return {AckCode::kErrGeneral, "no upload in progress (send UPLOAD_MOVE_BEGIN)"};
  // Every channel is checked before any is finalised: a refused END leaves the
  // upload open for the missing sections.
  for (const auto& [motor, track] : axes_) {
    if (!Covered(track)) {
      return {AckCode::kErrGeneral,
              "motor " + std::to_string(motor) + " has frames never uploaded and no last set"};
    }
  }
  for (const auto& [channel, track] : dmx_) {
    if (!Covered(track)) {
      return {AckCode::kErrGeneral, "DMX channel " + std::to_string(channel) +
                                        " has frames never uploaded and no last set"};
    }
  }
  for (auto& [motor, track] : axes_) Finalize(track);
  for (auto& [channel, track] : dmx_) Finalize(track);
  in_progress_ = false;
  complete_ = true;
  return {};
}

std::vector<int> RtMove::Motors() const {
  std::vector<int> out;
  for (const auto& [motor, track] : axes_) out.push_back(motor);
  return out;
}

std::vector<int> RtMove::Channels() const {
  std::vector<int> out;
  for (const auto& [channel, track] : dmx_) out.push_back(channel);
  return out;
}

bool RtMove::HasMotor(int motor) const { return axes_.count(motor) != 0; }

int32_t RtMove::Position(int motor, uint32_t frame) const {
  return axes_.at(motor).values[frame - start_];
}

uint8_t RtMove::Level(int channel, uint32_t frame) const {
  return dmx_.at(channel).values[frame - start_];
}

uint32_t RtMove::TriggersAt(uint32_t frame) const {
  auto it = triggers_.find(frame - start_);
  return it == triggers_.end() ? 0 : it->second;
}

size_t RtMove::HeapBytes() const {
  size_t n = 0;
  for (const auto& [m, t] : axes_)
    n += t.values.capacity() * sizeof(int32_t) + t.have.capacity() / 8 + 64;
  for (const auto& [c, t] : dmx_) n += t.values.capacity() + t.have.capacity() / 8 + 64;
  n += triggers_.size() * 48;
  return n;
}

}  // namespace moco::devices
