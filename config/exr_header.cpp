#include "config/exr_header.hpp"

#include <algorithm>
#include <fstream>
#include <vector>

#include "core/engine/decode.hpp"

namespace ph {
namespace {

constexpr std::uint8_t kMagic[4] = {0x76, 0x2f, 0x31, 0x01};  // 20000630, little-endian
constexpr std::uint32_t kMultipartFlag = 0x1000;
constexpr std::size_t kLongestName = 255;    // with the "long names" flag; 31 without
constexpr std::size_t kHeadBytes = 1 << 20;  // headers of real files end well before this

std::uint32_t little_endian32(const std::uint8_t* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}

// Walks the bytes of one or more headers. `at` is the offset of the next byte to read.
class HeaderWalk {
 public:
  HeaderWalk(std::span<const std::uint8_t> head, std::uint64_t file_size) : head_(head), file_size_(file_size) {}

  bool shown(std::size_t n) const { return at_ + n <= head_.size(); }
  bool in_file(std::uint64_t n) const { return at_ + n <= file_size_; }
  std::uint8_t byte() const { return head_[at_]; }
  std::uint64_t left() const { return file_size_ - std::min<std::uint64_t>(at_, file_size_); }
  void skip(std::uint64_t n) { at_ += n; }

  bool head_is_whole() const { return head_.size() >= file_size_; }

  // A NUL-terminated name at `at`: its text, or nothing when no NUL comes within kLongestName bytes or
  // before `head` ends (`cut` then says that `head` ended first).
  std::optional<std::string> name(bool& cut) {
    const std::size_t end = std::min(head_.size(), static_cast<std::size_t>(at_ + kLongestName + 1));
    for (std::size_t i = at_; i < end; ++i) {
      if (head_[i] == 0) {
        std::string text(head_.begin() + static_cast<std::ptrdiff_t>(at_),
                         head_.begin() + static_cast<std::ptrdiff_t>(i));
        at_ = i + 1;
        return text;
      }
    }
    cut = end == head_.size() && end - at_ <= kLongestName;
    return std::nullopt;
  }
  std::uint32_t word() {
    const std::uint32_t value = little_endian32(head_.data() + at_);
    at_ += 4;
    return value;
  }

 private:
  std::span<const std::uint8_t> head_;
  std::uint64_t file_size_;
  std::uint64_t at_ = 0;
};

// One header: attributes up to an empty name. Nothing when it is sound or `head` ends before it does
// (`unchecked` is then set).
std::optional<std::string> header_problem(HeaderWalk& walk, bool& unchecked) {
  const auto cut_off = [&]() -> std::optional<std::string> {
    unchecked = !walk.head_is_whole();
    if (unchecked) return std::nullopt;
    return "the file ends inside its header";
  };
  while (true) {
    if (!walk.shown(1)) return cut_off();
    if (walk.byte() == 0) {
      walk.skip(1);
      return std::nullopt;
    }
    bool cut = false;
    const std::optional<std::string> attribute = walk.name(cut);
    if (!attribute) return cut ? cut_off() : "an attribute name is longer than 255 bytes";
    const std::optional<std::string> type = walk.name(cut);
    if (!type) return cut ? cut_off() : "attribute '" + *attribute + "' has a type name longer than 255 bytes";
    if (!walk.shown(4)) return cut_off();
    const auto size = static_cast<std::int32_t>(walk.word());
    if (size < 0) return "attribute '" + *attribute + "' has a negative size (" + std::to_string(size) + ")";
    if (!walk.in_file(static_cast<std::uint64_t>(size))) {
      return "attribute '" + *attribute + "' claims " + std::to_string(size) + " bytes, and the file has " +
             std::to_string(walk.left()) + " left";
    }
    walk.skip(static_cast<std::uint64_t>(size));
  }
}

}  // namespace

std::optional<std::string> exr_header_problem(std::span<const std::uint8_t> head, std::uint64_t file_size) {
  if (head.size() < 8 || !std::equal(std::begin(kMagic), std::end(kMagic), head.begin())) {
    return file_size < 8 ? "too short for an OpenEXR file" : "not an OpenEXR file (no magic number)";
  }
  const bool multipart = (little_endian32(head.data() + 4) & kMultipartFlag) != 0;
  HeaderWalk walk(head, file_size);
  walk.skip(8);
  do {
    bool unchecked = false;
    if (std::optional<std::string> problem = header_problem(walk, unchecked)) return problem;
    if (unchecked) return std::nullopt;
    // Multi-part files list headers up to an empty one.
  } while (multipart && walk.shown(1) && walk.byte() != 0);
  return std::nullopt;
}

void check_exr_header(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return;  // the reader says why it cannot open it
  file.seekg(0, std::ios::end);
  const std::streamoff size = file.tellg();
  if (size < 0) return;
  file.seekg(0);
  std::vector<std::uint8_t> head(std::min<std::uint64_t>(static_cast<std::uint64_t>(size), kHeadBytes));
  file.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(file.gcount()));
  if (std::optional<std::string> problem = exr_header_problem(head, static_cast<std::uint64_t>(size))) {
    throw FieldError(path.string() + ": " + *problem);
  }
}

}  // namespace ph
