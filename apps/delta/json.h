#pragma once

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <string_view>

#include "delta/core/vec3.h"

namespace delta::cli {

/// A minimal streaming JSON writer for `--json` output: one object, keys in insertion order,
/// doubles at full precision (round-trip), non-finite numbers as null.
///
/// Threading: one writer per thread.
class JsonWriter {
 public:
  JsonWriter& beginObject(std::string_view key = {}) { return open(key, '{'); }
  JsonWriter& endObject() { return close('}'); }
  JsonWriter& beginArray(std::string_view key = {}) { return open(key, '['); }
  JsonWriter& endArray() { return close(']'); }

  JsonWriter& value(std::string_view key, double number) {
    return raw(key, std::isfinite(number) ? format(number) : "null");
  }
  JsonWriter& value(std::string_view key, std::size_t number) {
    return raw(key, std::to_string(number));
  }
  JsonWriter& value(std::string_view key, int number) { return raw(key, std::to_string(number)); }
  JsonWriter& value(std::string_view key, bool flag) { return raw(key, flag ? "true" : "false"); }
  JsonWriter& value(std::string_view key, std::string_view text) { return raw(key, quote(text)); }
  JsonWriter& value(std::string_view key, const char* text) {
    return value(key, std::string_view(text));
  }
  JsonWriter& value(std::string_view key, const Vec3& v) {
    return beginArray(key).value({}, v.x).value({}, v.y).value({}, v.z).endArray();
  }
  JsonWriter& null(std::string_view key) { return raw(key, "null"); }

  const std::string& str() const { return text_; }

 private:
  static std::string format(double number) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.17g", number);
    return buffer;
  }
  static std::string quote(std::string_view text) {
    std::string quoted = "\"";
    for (char c : text) {
      if (c == '"' || c == '\\') {
        quoted += '\\';
        quoted += c;
      } else if (static_cast<unsigned char>(c) < 0x20) {
        char escape[8];
        std::snprintf(escape, sizeof escape, "\\u%04x", c);
        quoted += escape;
      } else {
        quoted += c;
      }
    }
    return quoted + "\"";
  }
  JsonWriter& raw(std::string_view key, std::string_view literal) {
    separate();
    if (!key.empty()) text_ += quote(key) + ":";
    text_ += literal;
    return *this;
  }
  JsonWriter& open(std::string_view key, char bracket) {
    raw(key, std::string_view(&bracket, 1));
    first_ = true;
    return *this;
  }
  JsonWriter& close(char bracket) {
    text_ += bracket;
    first_ = false;
    return *this;
  }
  void separate() {
    if (!first_ && !text_.empty()) text_ += ',';
    first_ = false;
  }

  std::string text_;
  bool first_ = true;
};

}  // namespace delta::cli
