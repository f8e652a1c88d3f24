#include "layout.h"

#include <cstring>
#include <nlohmann/json.hpp>
#include <type_traits>

namespace hapticut::servo {

PointsView points_view(unsigned char* block, std::size_t points) {
  auto* q = reinterpret_cast<double*>(block);
  return {q, q + points * 3, block + points * 6 * sizeof(double)};
}

namespace {

template <typename T>
const char* numpy_code() {
  if constexpr (std::is_same_v<T, char>) return "S1";
  if constexpr (std::is_same_v<T, std::uint8_t>) return "u1";
  if constexpr (std::is_same_v<T, std::uint16_t>) return "u2";
  if constexpr (std::is_same_v<T, std::uint32_t>) return "u4";
  if constexpr (std::is_same_v<T, std::uint64_t>) return "u8";
  if constexpr (std::is_same_v<T, std::int32_t>) return "i4";
  if constexpr (std::is_same_v<T, double>) return "f8";
}

template <typename Struct>
nlohmann::json describe(nlohmann::json fields) {
  return {{"size", sizeof(Struct)}, {"fields", std::move(fields)}};
}

}  // namespace

#define HAPTICUT_DESCRIBE_FIELD(type, name)             \
  fields.push_back({{"name", #name},                    \
                    {"type", numpy_code<type>()},       \
                    {"offset", offsetof(STRUCT, name)}, \
                    {"shape", nlohmann::json::array()}});
#define HAPTICUT_DESCRIBE_ARRAY(type, name, count)      \
  fields.push_back({{"name", #name},                    \
                    {"type", numpy_code<type>()},       \
                    {"offset", offsetof(STRUCT, name)}, \
                    {"shape", {count}}});

std::string layout_json() {
  nlohmann::json out;
  out["frame_version"] = kFrameVersion;
  out["record_version"] = kRecordVersion;
  out["max_frame_bytes"] = kMaxFrameBytes;
  {
    nlohmann::json fields = nlohmann::json::array();
#define STRUCT FrameHeader
    HAPTICUT_FRAME_HEADER_FIELDS(HAPTICUT_DESCRIBE_FIELD, HAPTICUT_DESCRIBE_ARRAY)
#undef STRUCT
    out["frame_header"] = describe<FrameHeader>(fields);
  }
  {
    nlohmann::json fields = nlohmann::json::array();
#define STRUCT RecordHeader
    HAPTICUT_RECORD_HEADER_FIELDS(HAPTICUT_DESCRIBE_FIELD, HAPTICUT_DESCRIBE_ARRAY)
#undef STRUCT
    out["record_header"] = describe<RecordHeader>(fields);
  }
  {
    nlohmann::json fields = nlohmann::json::array();
#define STRUCT BladeBlock
    HAPTICUT_BLADE_BLOCK_FIELDS(HAPTICUT_DESCRIBE_FIELD, HAPTICUT_DESCRIBE_ARRAY)
#undef STRUCT
    out["blade_block"] = describe<BladeBlock>(fields);
  }
  {
    nlohmann::json fields = nlohmann::json::array();
#define STRUCT CutBlock
    HAPTICUT_CUT_BLOCK_FIELDS(HAPTICUT_DESCRIBE_FIELD, HAPTICUT_DESCRIBE_ARRAY)
#undef STRUCT
    out["cut_block"] = describe<CutBlock>(fields);
  }
  {
    nlohmann::json fields = nlohmann::json::array();
#define STRUCT RecordingTrailer
    HAPTICUT_RECORDING_TRAILER_FIELDS(HAPTICUT_DESCRIBE_FIELD, HAPTICUT_DESCRIBE_ARRAY)
#undef STRUCT
    out["recording_trailer"] = describe<RecordingTrailer>(fields);
  }
  out["points_block"] = {{"arrays",
                          {{{"name", "q"}, {"type", "f8"}, {"per_point", 3}},
                           {{"name", "p"}, {"type", "f8"}, {"per_point", 3}},
                           {{"name", "state"}, {"type", "u1"}, {"per_point", 1}}}},
                         {"align", 8}};
  return out.dump();
}

}  // namespace hapticut::servo
