#pragma once
// Turns a refused camera open into what the user must do. A ZED-class camera
// on a USB 2 port (or a USB 2 cable or hub) enumerates only its VGA
// side-by-side modes (1344x376); asking it for HD, FHD or 2K then fails at
// format negotiation with a list of offered sizes that says nothing about
// USB. Pure functions of the requested mode and what the device gave or
// offered, so they are tested without Linux (the caller takes both from
// hal::V4l2OpenFailure: `given` and `offered`).
#include <string>
#include <string_view>

#include "drivers/camera/camera_modes.hpp"
#include "hal/video_stream.hpp"

namespace rtfuse::drivers {

// True when a mode above VGA was asked for and the device offers (or, if
// `offered` lists no YUYV sizes, gave) only VGA-sized side-by-side frames.
// `offered` is V4l2Stream::describe_offered()'s text:
// "YUYV 1344x376 @15/30/60/100; MJPG 1280x720 @30".
bool looks_like_usb2(const CameraMode& requested, const hal::VideoFormat& given, std::string_view offered);

// The hint to append to the open error, or "" when the failure does not look
// like USB 2.
std::string zed_usb2_hint(const CameraMode& requested, const hal::VideoFormat& given, std::string_view offered);

}  // namespace rtfuse::drivers
