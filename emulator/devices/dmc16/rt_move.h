// The uploaded real-time move of a DMC v2 device (dmc-v2-protocol.txt
// MSG_RT_UPLOAD_MOVE_BEGIN / _AXIS / _DMX / _TRIGGERS / _END): per-motor
// positions and per-channel DMX levels for frames START..END, with the
// "last set" rule (the final value repeats to the end of the range).
#ifndef MOCO_DEVICES_DMC16_RT_MOVE_H_
#define MOCO_DEVICES_DMC16_RT_MOVE_H_

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "wire/dmc.h"

namespace moco::devices {

// Outcome of an upload step: OK or the ACK error code, with a reason for logs.
struct UploadResult {
  dmc::AckCode code = dmc::AckCode::kOk;
  std::string reason;
  bool ok() const { return code == dmc::AckCode::kOk; }
};

class RtMove {
 public:
  // REQUIRES: max_frames > 0. Channels are checked against these counts.
  RtMove(uint32_t max_frames, int motor_count, int dmx_channels);

  // BEGIN: clears any previous move. ERR_RANGE when END < START or the range
  // holds more frames than the device advertises (HI UPLOAD FRAME COUNT).
  UploadResult Begin(uint32_t start_frame, uint32_t end_frame);
  // AXIS / DMX / TRIGGERS: ERR_GENERAL outside BEGIN..END; ERR_RANGE for an
  // unknown motor or channel, or indices past the range. A section may be
  // sent again (a retry after ERR_CHECKSUM): later data overwrites.
  UploadResult Axis(const dmc::RtUploadMoveAxis& m);
  UploadResult Dmx(const dmc::RtUploadMoveDmx& m);
  UploadResult Triggers(const dmc::RtUploadMoveTriggers& m);
  // Whether Triggers refuses a frame index past the range (ERR_RANGE, the
  // default); unchecked, such a point is dropped and the section taken
  // (profile behaviour.trigger_frames_checked, dmc-lite).
  void SetTriggerFramesChecked(bool checked) { trigger_frames_checked_ = checked; }
  // END: ERR_GENERAL without BEGIN, or when a channel that was sent has
  // frames neither uploaded nor covered by its last set (a gap would leave
  // the device without a position for that frame).
  UploadResult End();
  void Clear();

  bool in_progress() const { return in_progress_; }
  bool complete() const { return complete_; }
  uint32_t start_frame() const { return start_; }
  uint32_t end_frame() const { return end_; }
  uint32_t frames() const { return frames_; }
  bool Contains(uint32_t frame) const { return complete_ && frame >= start_ && frame <= end_; }

  // Motors (1-based) and channels with data, in order.
  std::vector<int> Motors() const;
  std::vector<int> Channels() const;
  bool HasMotor(int motor) const;
  // REQUIRES: complete(), Contains(frame), HasMotor(motor).
  int32_t Position(int motor, uint32_t frame) const;
  // REQUIRES: complete(), Contains(frame), the channel has data.
  uint8_t Level(int channel, uint32_t frame) const;
  uint32_t trigger_mask() const { return trigger_mask_; }
  // Trigger values at a frame (0 for frames without an entry: the host sends
  // only frames where a trigger is on).
  uint32_t TriggersAt(uint32_t frame) const;

  size_t HeapBytes() const;

 private:
  template <typename T>
  struct Track {
    std::vector<T> values;
    std::vector<bool> have;
    bool last_set = false;
    uint32_t repeat_from = 0;  // with last_set: values from here repeat values[repeat_from-1]
  };
  template <typename T>
  UploadResult Store(std::map<int, Track<T>>& tracks, int key, uint32_t start_index, bool last_set,
                     const std::vector<T>& values);
  template <typename T>
  bool Covered(const Track<T>& track) const;
  template <typename T>
  void Finalize(Track<T>& track) const;

  uint32_t max_frames_;
  int motor_count_;
  int dmx_channels_;
  bool in_progress_ = false;
  bool complete_ = false;
  uint32_t start_ = 0;
  uint32_t end_ = 0;
  uint32_t frames_ = 0;
  std::map<int, Track<int32_t>> axes_;
  std::map<int, Track<uint8_t>> dmx_;
  uint32_t trigger_mask_ = 0;
  bool trigger_frames_checked_ = true;
  std::map<uint32_t, uint32_t> triggers_;  // frame index -> values
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_RT_MOVE_H_
