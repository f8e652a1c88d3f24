// A load in parts, so that reading, parsing and building a scene happen off
// the control thread: a `load` message becomes a LoadRequest on the control
// thread (its fields checked, nothing read), a PreparedLoad on the control
// server's worker (the file read, the scene parsed, the Space, the devices and
// the recorder built), and the Servo installs it (Servo::install).
#pragma once

#include <functional>
#include <memory>

#include "control_message.h"
#include "load_worker.h"
#include "recording/recorder.h"
#include "session.h"

namespace hapticut::servo {

struct PreparedLoad {
  std::unique_ptr<Session> session;
  std::unique_ptr<Recorder> recorder;
};

// What a `load` message asks for: the session's settings and, for a scene
// sent inline, its tree (turned back into text on the worker, not here).
struct LoadRequest {
  SessionConfig config;
  ControlJson inline_scene;
};

// The message's fields over `base` (the command line's settings). Throws
// CommandError naming a field; reads no file.
LoadRequest load_request(ControlJson& message, SessionConfig base);

// The session and its recorder (record_buffer_s of records). Throws as
// Session does; `between_stages` as Session's.
PreparedLoad prepare_load(
    const SessionConfig& config, double record_buffer_s,
    const std::function<void()>& between_stages = [] {});

// prepare_load for a client's `load`, stopping between stages when asked
// (LoadCancelled), with the errors a client is told: a file is named, never
// quoted, and one that is not a scene is "not a hapticut scene file".
PreparedLoad prepare_requested_load(LoadRequest request, double record_buffer_s,
                                    const LoadStop& stop);

}  // namespace hapticut::servo
