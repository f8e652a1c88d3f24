#include "session_load.h"

#include <string>
#include <utility>

#include "client_files.h"
#include "hapticut/scene_io.h"
#include "servo_loop.h"

namespace hapticut::servo {

LoadRequest load_request(ControlJson& message, SessionConfig base) {
  LoadRequest request;
  SessionConfig& config = request.config;
  config = std::move(base);
  config.scene_path.clear();
  if (has_field(message, "path") && has_field(message, "scene")) {
    throw CommandError("load takes \"path\" or \"scene\", not both");
  }
  if (has_field(message, "path")) {
    config.scene_path = string_field(message, "path", kMaxPathBytes);
  } else if (has_field(message, "scene")) {
    if (!message.at("scene").is_object()) throw CommandError("scene: expected an object");
    // Moved, not copied: an inline scene is up to a message's 16 MiB.
    request.inline_scene = std::move(message.at("scene"));
  } else {
    throw CommandError("load needs \"path\" or \"scene\"");
  }
  if (has_field(message, "devices")) {
    const ControlJson& devices = message.at("devices");
    if (!devices.is_array() || devices.size() > kMaxBlades) {
      throw CommandError("devices: expected a list of at most " + std::to_string(kMaxBlades) +
                         " --device texts");
    }
    config.devices.clear();
    config.remote_bridge_allowed = false;  // A client's texts bind loopback only.
    for (const ControlJson& d : devices) {
      if (!d.is_string() || d.get_ref<const std::string&>().empty() ||
          d.get_ref<const std::string&>().size() > kMaxNameBytes) {
        throw CommandError("devices: expected strings of 1 to " + std::to_string(kMaxNameBytes) +
                           " bytes");
      }
      config.devices.push_back(d.get<std::string>());
    }
  }
  if (has_field(message, "rate_Hz")) {
    config.rate_Hz = number_field(message, "rate_Hz", 1.0, kMaxRate_Hz);
  }
  if (has_field(message, "as_fast_as_possible")) {
    config.as_fast_as_possible = boolean_field(message, "as_fast_as_possible");
  }
  return request;
}

PreparedLoad prepare_load(const SessionConfig& config, double record_buffer_s,
                          const std::function<void()>& between_stages) {
  PreparedLoad prepared;
  prepared.session = std::make_unique<Session>(config, between_stages);
  prepared.recorder = std::make_unique<Recorder>(prepared.session->recording_info(),
                                                 prepared.session->rate_Hz(), record_buffer_s);
  return prepared;
}

PreparedLoad prepare_requested_load(LoadRequest request, double record_buffer_s,
                                    const LoadStop& stop) {
  SessionConfig& config = request.config;
  if (!request.inline_scene.is_null()) {
    config.scene_json = request.inline_scene.dump();
    request.inline_scene = ControlJson();
  }
  try {
    return prepare_load(config, record_buffer_s, [&stop] { stop.check(); });
  } catch (const FileRefused& e) {
    throw CommandError(std::string("scene: ") + e.what());
  } catch (const SceneError& e) {
    if (config.scene_path.empty()) throw;
    // A file that is not a scene: say so, not what its "format" holds.
    throw CommandError("scene: '" + config.scene_path + "': " +
                       (e.field() == "/format" ? std::string("not a hapticut scene file")
                                               : std::string(e.what())));
  }
}

}  // namespace hapticut::servo
