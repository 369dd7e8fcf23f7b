#pragma once
// A minimal JSON object writer for summaries (flat keys, numbers, strings and
// arrays of integers).
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

namespace snl {

class JsonObject {
 public:
  JsonObject& add(const std::string& key, const std::string& v) {
    sep();
    os_ << quote(key) << ": " << quote(v);
    return *this;
  }
  JsonObject& add(const std::string& key, const char* v) { return add(key, std::string(v)); }
  JsonObject& add(const std::string& key, double v) {
    sep();
    os_ << quote(key) << ": ";
    if (std::isfinite(v)) {
      std::ostringstream t;
      t.precision(17);
      t << v;
      os_ << t.str();
    } else {
      os_ << "null";
    }
    return *this;
  }
  JsonObject& add(const std::string& key, std::int64_t v) {
    sep();
    os_ << quote(key) << ": " << v;
    return *this;
  }
  JsonObject& add(const std::string& key, int v) { return add(key, static_cast<std::int64_t>(v)); }
  /// An array of integers.
  JsonObject& add(const std::string& key, const std::vector<std::int64_t>& v) { return add_array(key, v); }
  JsonObject& add_array(const std::string& key, const std::vector<std::int64_t>& v) {
    sep();
    os_ << quote(key) << ": [";
    for (std::size_t i = 0; i < v.size(); ++i) os_ << (i ? ", " : "") << v[i];
    os_ << "]";
    return *this;
  }
  JsonObject& add_null(const std::string& key) {
    sep();
    os_ << quote(key) << ": null";
    return *this;
  }
  JsonObject& add_bool(const std::string& key, bool v) {
    sep();
    os_ << quote(key) << ": " << (v ? "true" : "false");
    return *this;
  }
  std::string str() const { return "{\n" + os_.str() + "\n}\n"; }

  static std::string quote(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
      if (c == '"' || c == '\\') {
        o += '\\';
        o += c;
      } else if (static_cast<unsigned char>(c) < 0x20) {
        char b[8];
        std::snprintf(b, sizeof b, "\\u%04x", c);
        o += b;
      } else {
        o += c;
      }
    }
    return o + "\"";
  }

 private:
  void sep() {
    if (!first_) os_ << ",\n";
    os_ << "  ";
    first_ = false;
  }
  std::ostringstream os_;
  bool first_ = true;
};

/// Writes text atomically (temporary file + rename). Throws snl::Error.
void write_text_atomic(const std::string& path, const std::string& text);

}  // namespace snl
