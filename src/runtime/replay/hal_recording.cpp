#include "runtime/replay/hal_recording.hpp"

#include <algorithm>
#include <string_view>
#include <utility>

namespace rtfuse {
namespace {

using hal::BusEvent;
using transport::DeviceKind;
using transport::EventLogReader;
using transport::HalRecordCodec;
using transport::LogEvent;
using transport::LoopTick;
using transport::ReadStatus;
using transport::RecordedDevice;
using transport::RecordedFile;
using transport::RecordingEnd;
using transport::kHalChannelPrefix;
using transport::kLoopTickChannel;
using transport::kRecordChannelPrefix;
using transport::kRecordedFileChannel;
using transport::kRecordingEndChannel;
using transport::kRecordingInfoChannel;

void set_error(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

bool starts_with(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && s.substr(0, prefix.size()) == prefix;
}

}  // namespace

bool load_hal_recording(EventLogReader& reader, const HalRecordingOptions& options, HalRecording* out,
                        std::string* error) {
  HalRecording rec;
  const std::string& path = reader.path();
  LogEvent ev;
  std::string read_error;

  ReadStatus st = reader.next(&ev, &read_error);
  if (st == ReadStatus::kEnd) {
    set_error(error, "file " + path + " is empty: not an rtfuse HAL recording (rtfused --record writes one)");
    return false;
  }
  if (st == ReadStatus::kError) {
    set_error(error, read_error);
    return false;
  }
  if (ev.channel != kRecordingInfoChannel) {
    set_error(error, "file " + path + " is not an rtfuse HAL recording: event " + std::to_string(ev.event_number) +
                         " is on channel '" + std::string(ev.channel) + "', a recording starts with a " +
                         "recording_info_t on " + std::string(kRecordingInfoChannel) +
                         " (a log of sensor messages replays with rtfuse-replay --log)");
    return false;
  }
  std::string why;
  if (!transport::decode_recording_info(ev.data, static_cast<int>(ev.size), &rec.info, &why)) {
    set_error(error, "file " + path + ": event " + std::to_string(ev.event_number) + " on " +
                         std::string(kRecordingInfoChannel) + ": " + why);
    return false;
  }
  rec.events = 1;

  HalRecordCodec codec(rec.info.devices);
  for (const std::string& name : rec.info.streams) {
    rec.streams.push_back(std::make_unique<hal::replay::ReplayStream>(name));
    rec.videos.push_back(std::make_unique<hal::replay::ReplayVideoLog>(name));
  }
  for (std::size_t i = 0; i < rec.info.devices.size(); ++i) {
    const RecordedDevice& d = rec.info.devices[i];
    for (auto& s : rec.streams) s->set_device_name(static_cast<std::uint8_t>(i), d.name);
    for (auto& v : rec.videos) v->set_device_name(static_cast<std::uint8_t>(i), d.name);
  }
  std::vector<bool> holed(rec.streams.size(), false);
  bool have_tick = false;
  std::int64_t last_seq = 0;

  auto undecodable = [&](const LogEvent& e, const std::string& reason) {
    set_error(error, "file " + path + ": event " + std::to_string(e.event_number) + " on channel " +
                         std::string(e.channel) + " cannot be decoded: " + reason);
    return false;
  };

  std::uint64_t frame_bytes = 0;  // ReplayVideoLog's, all streams
  bool ended = false;
  // A log cut short: mid-event, or between two events without the end
  // record. Allowed, its complete events are kept.
  auto cut_short = [&](const std::string& how, const std::string& detail) {
    const std::int64_t complete = reader.events_read();
    const std::string what = "file " + path + ": " + how + " after event " + std::to_string(complete - 1) +
                             ", the recorder was probably killed or lost power";
    if (!options.allow_truncated) {
      set_error(error, what + ": replay the first " + std::to_string(complete) + " events with --allow-truncated (" +
                           detail + ")");
      return false;
    }
    rec.truncated = true;
    rec.warnings.push_back(what + ": replaying its first " + std::to_string(complete) + " events");
    return true;
  };

  for (;;) {
    st = reader.next(&ev, &read_error);
    if (st == ReadStatus::kEnd) {
      if (!ended && !cut_short("ends", "no rtfuse/rec/end record, which a recorder that stops writes last")) {
        return false;
      }
      break;
    }
    if (st == ReadStatus::kError) {
      const bool truncated = read_error.find("the log ends mid-event") != std::string::npos;
      if (!truncated) {
        set_error(error, read_error);
        return false;
      }
      if (!cut_short("truncated", read_error)) return false;
      break;
    }
    ++rec.events;
    if (ended) return undecodable(ev, "an event after the end of the recording (two recordings concatenated?)");
    const int size = static_cast<int>(ev.size);
    DeviceKind kind = DeviceKind::kCan;
    if (starts_with(ev.channel, kHalChannelPrefix) && codec.kind_of(codec.device_of(ev.channel), &kind) &&
        kind == DeviceKind::kVideo) {
      hal::VideoEvent video;
      const std::uint8_t* frame = nullptr;
      if (!codec.decode_video(ev.channel, ev.data, size, &video, &frame, &why)) return undecodable(ev, why);
      const auto stream = static_cast<std::size_t>(rec.info.devices[video.device].stream);
      if (holed[stream]) continue;
      hal::replay::ReplayVideoLog& log = *rec.videos[stream];
      if (video.lost_before > 0) {
        // As for bus events: the lost calls are unknown, the stream ends here.
        holed[stream] = true;
        log.mark_hole(ev.event_number, video.lost_before, video.frames_before);
        rec.lost_events += video.lost_before;
        rec.lost_frames += log.lost_frames();
        std::string what = std::to_string(video.lost_before) + " calls";
        if (log.lost_frames() > 0) {
          what += " (frames " + std::to_string(log.first_lost_frame()) + ".." +
                  std::to_string(log.first_lost_frame() + log.lost_frames() - 1) + ")";
        }
        rec.warnings.push_back("stream '" + rec.info.streams[stream] + "': the recorder lost " + what +
                               " before event " + std::to_string(ev.event_number) +
                               " (its ring was full): this stream replays only up to there");
        continue;
      }
      if (video.has_frame()) {
        const std::uint64_t need = std::max<std::uint64_t>(video.data_size, video.length);
        frame_bytes += need;
        if (frame_bytes > options.max_frame_bytes) {
          set_error(error, "file " + path + ": event " + std::to_string(ev.event_number) + " on channel " +
                               std::string(ev.channel) + ": the camera frames up to here need " +
                               std::to_string(frame_bytes >> 20) + " MiB in memory (this one a buffer of " +
                               std::to_string(video.length) + " bytes), more than the " +
                               std::to_string(options.max_frame_bytes >> 20) +
                               " MiB allowed: a corrupt buffer length, or a recording to replay with a larger "
                               "--frame-memory on a machine that has it");
          return false;
        }
      }
      log.append(video, frame, ev.event_number);
    } else if (starts_with(ev.channel, kHalChannelPrefix)) {
      BusEvent bus;
      if (!codec.decode(ev.channel, ev.data, size, &bus, &why)) return undecodable(ev, why);
      const auto stream = static_cast<std::size_t>(rec.info.devices[bus.device].stream);
      if (holed[stream]) continue;
      if (bus.lost_before > 0) {
        // The calls lost before this one are unknown: nothing after them on
        // this thread can be replayed faithfully.
        holed[stream] = true;
        rec.lost_events += bus.lost_before;
        rec.streams[stream]->mark_hole(ev.event_number, bus.lost_before);
        rec.warnings.push_back("stream '" + rec.info.streams[stream] + "': the recorder lost " +
                               std::to_string(bus.lost_before) + " events before event " +
                               std::to_string(ev.event_number) +
                               " (its ring was full): this stream replays only up to there");
        continue;
      }
      rec.streams[stream]->append(bus, ev.event_number);
    } else if (ev.channel == kLoopTickChannel) {
      LoopTick tick;
      if (!HalRecordCodec::decode_tick(ev.data, size, &tick, &why)) return undecodable(ev, why);
      // Seqs are >= 0 (decode_tick) and rise, so differences cannot
      // overflow and the gaps add up to at most the last seq; last_seq + 1
      // could overflow, for a seq of INT64_MAX.
      if (have_tick && tick.seq <= last_seq) {
        return undecodable(ev, "tick seq " + std::to_string(tick.seq) + " after " + std::to_string(last_seq) +
                                   " goes backwards");
      }
      if (have_tick) rec.missing_ticks += tick.seq - last_seq - 1;
      have_tick = true;
      last_seq = tick.seq;
      rec.ticks.push_back(std::move(tick));
    } else if (ev.channel == kRecordedFileChannel) {
      RecordedFile file;
      if (!transport::decode_recorded_file(ev.data, size, &file, &why)) return undecodable(ev, why);
      rec.info.files.push_back(std::move(file));
      if (!transport::validate(rec.info, &why)) return undecodable(ev, why);
    } else if (ev.channel == kRecordingEndChannel) {
      RecordingEnd end;
      if (!transport::decode_recording_end(ev.data, size, &end, &why)) return undecodable(ev, why);
      if (end.events != rec.events - 1) {
        return undecodable(ev, "the end record counts " + std::to_string(end.events) + " events before it, the log holds " +
                                   std::to_string(rec.events - 1) + ": events are missing or were added");
      }
      ended = true;
    } else if (starts_with(ev.channel, transport::kRecordedInputPrefix)) {
      rec.inputs.push_back(RecordedOutput{std::string(ev.channel.substr(transport::kRecordedInputPrefix.size())),
                                          ev.timestamp_us, ev.event_number,
                                          std::vector<std::uint8_t>(ev.data, ev.data + ev.size)});
    } else if (starts_with(ev.channel, kRecordChannelPrefix)) {
      return undecodable(ev, ev.channel == kRecordingInfoChannel
                                 ? std::string("a second recording_info_t (two recordings concatenated?)")
                                 : std::string("unknown record channel (written by a newer rtfuse?)"));
    } else {
      rec.outputs.push_back(RecordedOutput{std::string(ev.channel), ev.timestamp_us, ev.event_number,
                                           std::vector<std::uint8_t>(ev.data, ev.data + ev.size)});
    }
  }
  if (rec.missing_ticks > 0) {
    rec.warnings.push_back(std::to_string(rec.missing_ticks) +
                           " loop ticks are missing (the recorder's tick ring was full)");
  }
  *out = std::move(rec);
  return true;
}

}  // namespace rtfuse
