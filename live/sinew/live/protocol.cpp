#include "sinew/live/protocol.hpp"

#include <cmath>
#include <cstring>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace sinew::live {

using nlohmann::json;

namespace {

double finite_number(const json& m, const char* key) {
  if (!m.contains(key)) throw ProtocolError(fmt::format("missing '{}'", key));
  const json& v = m.at(key);
  if (!v.is_number()) throw ProtocolError(fmt::format("'{}' must be a number", key));
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw ProtocolError(fmt::format("'{}' must be finite", key));
  return x;
}

std::array<double, 3> vec3(const json& m, const char* key) {
  if (!m.contains(key) || !m.at(key).is_array() || m.at(key).size() != 3)
    throw ProtocolError(fmt::format("'{}' must be a list of 3 numbers", key));
  std::array<double, 3> out{};
  for (std::size_t k = 0; k < 3; ++k) {
    const json& v = m.at(key)[k];
    if (!v.is_number()) throw ProtocolError(fmt::format("'{}' must be a list of 3 numbers", key));
    out[k] = v.get<double>();
    if (!std::isfinite(out[k])) throw ProtocolError(fmt::format("'{}' must be finite", key));
  }
  return out;
}

void allow(const json& m, std::initializer_list<const char*> keys) {
  for (const auto& [k, v] : m.items()) {
    bool ok = k == "type" || k == "id";
    for (const char* a : keys) ok = ok || k == a;
    if (!ok) throw ProtocolError(fmt::format("unknown key '{}' for this message type", k));
  }
}

template <typename T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}

template <typename T>
void put_all(std::string& out, const std::vector<T>& v) {
  out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

}  // namespace

const char* field_name(Field f) {
  switch (f) {
    case Field::von_mises:
      return "von_mises";
    case Field::jacobian:
      return "jacobian";
    default:
      return "displacement";
  }
}

Command parse_command(std::string_view text) {
  if (text.size() > kMaxMessageBytes)
    throw ProtocolError(
        fmt::format("message too long ({} bytes, at most {})", text.size(), kMaxMessageBytes));
  json m;
  try {
    m = json::parse(text);
  } catch (const json::exception&) {
    throw ProtocolError("malformed JSON");
  }
  if (!m.is_object()) throw ProtocolError("a message must be a JSON object");
  if (!m.contains("type") || !m.at("type").is_string())
    throw ProtocolError("missing 'type' (a string)");
  Command c;
  if (m.contains("id")) {
    const json& id = m.at("id");
    if (!id.is_number_unsigned() || id.get<std::uint64_t>() > 0xffffffffu)
      throw ProtocolError("'id' must be an integer in [0, 4294967295]");
    c.id = id.get<std::uint32_t>();
  }
  const std::string type = m.at("type").get<std::string>();
  if (type == "activation") {
    allow(m, {"muscle", "value"});
    if (!m.contains("muscle") || !m.at("muscle").is_string())
      throw ProtocolError("'muscle' must be a muscle name");
    c.kind = Command::Kind::activation;
    c.muscle = m.at("muscle").get<std::string>();
    if (!m.contains("value")) throw ProtocolError("missing 'value' (a number in [0, 1] or null)");
    if (!m.at("value").is_null()) {
      const double a = finite_number(m, "value");
      if (a < 0 || a > 1) throw ProtocolError(fmt::format("'value' {} outside [0, 1]", a));
      c.value = a;
    }
  } else if (type == "pause" || type == "resume" || type == "reset" || type == "release") {
    allow(m, {});
    c.kind = type == "pause"    ? Command::Kind::pause
             : type == "resume" ? Command::Kind::resume
             : type == "reset"  ? Command::Kind::reset
                                : Command::Kind::release;
  } else if (type == "step") {
    allow(m, {"count"});
    c.kind = Command::Kind::step;
    if (m.contains("count")) {
      const json& n = m.at("count");
      if (!n.is_number_integer() || n.get<std::int64_t>() < 1 ||
          n.get<std::int64_t>() > kMaxStepCount)
        throw ProtocolError(fmt::format("'count' must be an integer in [1, {}]", kMaxStepCount));
      c.count = n.get<std::int64_t>();
    }
  } else if (type == "drag") {
    allow(m, {"point", "force", "radius"});
    c.kind = Command::Kind::drag;
    c.point = vec3(m, "point");
    c.force = vec3(m, "force");
    c.radius = finite_number(m, "radius");
    if (!(c.radius > 0) || c.radius > kMaxDragRadius)
      throw ProtocolError(fmt::format("'radius' must be in (0, {}] m", kMaxDragRadius));
    const double f = std::hypot(c.force[0], c.force[1], c.force[2]);
    if (f > kMaxDragForce)
      throw ProtocolError(
          fmt::format("'force' {:.4g} N above the limit of {} N", f, kMaxDragForce));
  } else if (type == "record") {
    allow(m, {"on"});
    if (!m.contains("on") || !m.at("on").is_boolean())
      throw ProtocolError("'on' must be true or false");
    c.kind = Command::Kind::record;
    c.on = m.at("on").get<bool>();
  } else if (type == "seek") {
    allow(m, {"frame"});
    c.kind = Command::Kind::seek;
    if (!m.contains("frame") || !m.at("frame").is_number_integer() ||
        m.at("frame").get<std::int64_t>() < 0)
      throw ProtocolError("'frame' must be a frame index (an integer >= 0)");
    c.count = m.at("frame").get<std::int64_t>();
  } else if (type == "continue") {
    allow(m, {});
    c.kind = Command::Kind::resume_from;
  } else if (type == "field") {
    allow(m, {"field"});
    c.kind = Command::Kind::field;
    const std::string f = m.contains("field") && m.at("field").is_string()
                              ? m.at("field").get<std::string>()
                              : std::string();
    if (f == "displacement")
      c.field = Field::displacement;
    else if (f == "von_mises")
      c.field = Field::von_mises;
    else if (f == "jacobian")
      c.field = Field::jacobian;
    else
      throw ProtocolError("'field' must be displacement, von_mises or jacobian");
  } else {
    throw ProtocolError(fmt::format(
        "unknown message type '{}' (expected activation, pause, resume, step, reset, drag, "
        "release, record, field, seek or continue)",
        type.substr(0, 64)));
  }
  return c;
}

std::string error_message(const std::string& message, std::uint32_t id) {
  json j = {{"type", "error"}, {"message", message}};
  if (id) j["id"] = id;
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string encode_mesh(const std::vector<float>& rest,
                        const std::vector<std::uint32_t>& triangles) {
  std::string out;
  out.reserve(16 + 4 * (rest.size() + triangles.size()));
  put(out, kTagMesh);
  put(out, std::uint32_t(rest.size() / 3));
  put(out, std::uint32_t(triangles.size() / 3));
  put(out, std::uint32_t(0));
  put_all(out, rest);
  put_all(out, triangles);
  return out;
}

std::string encode_frame(std::int64_t step, double time, Field field, std::uint32_t command_id,
                         const std::vector<float>& displacement, const std::vector<float>& values) {
  std::string out;
  out.reserve(kFrameHeaderBytes + 4 * (displacement.size() + values.size()));
  put(out, kTagFrame);
  put(out, std::uint32_t(values.size()));
  put(out, std::uint32_t(field));
  put(out, command_id);
  put(out, double(step));
  put(out, time);
  put_all(out, displacement);
  put_all(out, values);
  return out;
}

}  // namespace sinew::live
