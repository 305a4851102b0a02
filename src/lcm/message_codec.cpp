#include "plsa/lcm/message_codec.hpp"

#include <cstring>

namespace plsa::lcm {
namespace {

// Walks an LCM encoding (big-endian fields) without trusting it: every read
// checks what is left, every count its limit. The first failure is kept.
class Walk {
 public:
  Walk(const void* data, std::size_t size, const char* type)
      : p_(static_cast<const std::uint8_t*>(data)), n_(size), type_(type) {}

  bool fingerprint(std::int64_t expected) {
    std::uint64_t v = 0;
    if (!big(8, "fingerprint", v)) return false;
    if (static_cast<std::int64_t>(v) != expected) return fail("fingerprint", "is not " + std::string(type_) + "'s");
    return true;
  }
  bool skip(std::size_t bytes, const char* field) {
    if (n_ - pos_ < bytes) return fail(field, "runs past the message's end");
    pos_ += bytes;
    return true;
  }
  bool count(const char* field, std::int32_t lo, std::int32_t hi, std::int32_t& value) {
    std::uint64_t v = 0;
    if (!big(4, field, v)) return false;
    value = static_cast<std::int32_t>(static_cast<std::uint32_t>(v));
    if (value < lo || value > hi)
      return fail(field,
                  "= " + std::to_string(value) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi));
    return true;
  }
  bool doubles(std::size_t count, const char* field) {
    return count <= (n_ - pos_) / 8 ? skip(8 * count, field) : fail(field, "runs past the message's end");
  }
  // LCM strings: an int32 length that counts the terminating NUL, the bytes, the NUL.
  bool string(const char* field) {
    std::int32_t len = 0;
    if (!count(field, 1, kMaxStringBytes, len)) return false;
    const std::size_t bytes = static_cast<std::size_t>(len);
    if (n_ - pos_ < bytes) return fail(field, "runs past the message's end");
    if (p_[pos_ + bytes - 1] != 0) return fail(field, "is not NUL-terminated");
    if (std::memchr(p_ + pos_, 0, bytes - 1) != nullptr) return fail(field, "has a NUL byte inside it");
    pos_ += bytes;
    return true;
  }
  bool end() {
    if (pos_ != n_) return fail("message", "has " + std::to_string(n_ - pos_) + " bytes after its last field");
    return true;
  }
  const std::string& why() const { return why_; }

 private:
  bool big(std::size_t bytes, const char* field, std::uint64_t& v) {
    if (n_ - pos_ < bytes) return fail(field, "runs past the message's end");
    v = 0;
    for (std::size_t i = 0; i < bytes; ++i) v = (v << 8) | p_[pos_ + i];
    pos_ += bytes;
    return true;
  }
  bool fail(const char* field, const std::string& what) {
    if (why_.empty())
      why_ = std::string(type_) + ": " + field + " " + what + " (" + std::to_string(n_) + "-byte message)";
    return false;
  }

  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
  const char* type_;
  std::string why_;
};

std::string sizeProblem(std::size_t size, const char* type) {
  if (size <= kMaxMessageBytes) return {};
  return std::string(type) + ": " + std::to_string(size) + " bytes, above the " +
         std::to_string(kMaxMessageBytes >> 20) + " MiB plsa accepts";
}

// The walk has checked every count and length; the generated decoder now reads
// the same bytes, and must consume all of them.
template <class Message>
std::string fill(const Walk& walk, const void* data, std::size_t size, Message& out, const char* type) {
  if (!walk.why().empty()) return walk.why();
  if (out.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size))
    return std::string(type) + ": the generated decoder disagreed with the checked walk";
  return {};
}

}  // namespace

std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::pressure_command_t& out) {
  const char* type = "plsa_lcm.pressure_command_t";
  if (std::string why = sizeProblem(size, type); !why.empty()) return why;
  Walk w(data, size, type);
  std::int32_t n = 0;
  (void)(w.fingerprint(plsa_lcm::pressure_command_t::getHash()) && w.skip(16, "utime/seq") &&
         w.count("n_chambers", 0, kMaxChambers, n) && w.doubles(static_cast<std::size_t>(n), "pressure_bar") &&
         w.end());
  return fill(w, data, size, out, type);
}

std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::actuator_state_t& out) {
  const char* type = "plsa_lcm.actuator_state_t";
  if (std::string why = sizeProblem(size, type); !why.empty()) return why;
  Walk w(data, size, type);
  std::int32_t n = 0;
  (void)(w.fingerprint(plsa_lcm::actuator_state_t::getHash()) && w.skip(16, "utime/seq") &&
         w.count("n_chambers", 0, kMaxChambers, n) && w.doubles(static_cast<std::size_t>(n), "command_bar") &&
         w.doubles(static_cast<std::size_t>(n), "pressure_bar") && w.doubles(2, "bend_deg/steer_deg") &&
         w.doubles(9, "sensor_rotation") && w.skip(1, "vented") && w.end());
  return fill(w, data, size, out, type);
}

std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::prediction_t& out) {
  const char* type = "plsa_lcm.prediction_t";
  if (std::string why = sizeProblem(size, type); !why.empty()) return why;
  Walk w(data, size, type);
  std::int32_t horizon = 0, outputs = 0;
  bool ok = w.fingerprint(plsa_lcm::prediction_t::getHash()) && w.skip(24, "utime/state_seq/sample_time_s") &&
            w.count("horizon", 0, kMaxPredictionSteps, horizon) &&
            w.count("n_outputs", 0, kMaxPredictionOutputs, outputs);
  for (std::int32_t i = 0; ok && i < outputs; ++i) ok = w.string("output_names[]");
  (void)(ok && w.doubles(static_cast<std::size_t>(horizon) * static_cast<std::size_t>(outputs), "trajectory") &&
         w.end());
  return fill(w, data, size, out, type);
}

std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::status_t& out) {
  const char* type = "plsa_lcm.status_t";
  if (std::string why = sizeProblem(size, type); !why.empty()) return why;
  Walk w(data, size, type);
  std::int32_t n = 0;
  bool ok = w.fingerprint(plsa_lcm::status_t::getHash()) && w.skip(8, "utime") && w.string("source") &&
            w.skip(1, "state") && w.string("message") && w.count("n_values", 0, kMaxStatusValues, n);
  for (std::int32_t i = 0; ok && i < n; ++i) ok = w.string("names[]");
  (void)(ok && w.doubles(static_cast<std::size_t>(n), "values") && w.end());
  return fill(w, data, size, out, type);
}

}  // namespace plsa::lcm
