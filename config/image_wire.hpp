// The messages between the daemon and its image reader child (config/image_child.hpp): a request for a
// region's fields or an image's size, and the answer. Both ends are built together from these
// definitions; still, the daemon reads an answer as it would read anything from a process that parsed
// a hostile file: every length is bounded and checked, every value must be finite, and a message that
// is not right is an error (WireError), never a crash or a NaN in a field.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "config/field_loader.hpp"
#include "config/image_io.hpp"

namespace ph::image_wire {

class WireError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// At most this many bytes in one message: two full fields of the largest image the limits allow.
inline constexpr std::uint64_t kMaxMessage = std::uint64_t{1} << 31;

struct FieldsRequest {
  FieldSources sources;
  std::int32_t width = 0;
  std::int32_t height = 0;
  FieldNeeds needs;
};
struct SizeRequest {
  std::filesystem::path path;
};
using Request = std::variant<FieldsRequest, SizeRequest>;

struct FieldsAnswer {
  RegionFields fields;
  FieldLoadReport report;
};
struct Failure {
  std::string message;  // a FieldError's, naming the file
};
using Answer = std::variant<FieldsAnswer, ImageSize, Failure>;

std::vector<std::byte> encode(const Request& request);
Request decode_request(const std::vector<std::byte>& bytes);
std::vector<std::byte> encode(const Answer& answer);
// Checks the answer against the request it answers: a FieldsAnswer must hold exactly the fields the
// request needs, at its size, with finite values (slopes within kMaxSlope).
Answer decode_answer(const std::vector<std::byte>& bytes, const Request& request);

// A message on a pipe: its length (8 bytes) then its bytes. write_message throws WireError on a failed
// write; read_message returns false at end of file before the first byte, throws WireError on a short
// or oversized message, or one that is not all there by `deadline` (when given).
void write_message(int fd, const std::vector<std::byte>& bytes);
bool read_message(int fd, std::vector<std::byte>& bytes,
                  std::optional<std::chrono::steady_clock::time_point> deadline = std::nullopt);

}  // namespace ph::image_wire
