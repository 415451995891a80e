#include "config/exr_header.hpp"

#include <algorithm>
#include <fstream>
#include <string_view>
#include <utility>
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
  std::span<const std::uint8_t> bytes(std::size_t n) const { return head_.subspan(at_, n); }
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

// The size of the value of each attribute type OpenEXR reads as a fixed structure, whatever size the file
// gives (the OpenEXR file layout's table of attribute types). A file that gives another size would be read from
// another place than its size field says: it is refused, so that this walk and OpenEXR's read the same bytes.
std::optional<std::size_t> fixed_size(const std::string& type) {
  static constexpr std::pair<std::string_view, std::size_t> kFixed[] = {{"box2i", 16},
                                                                        {"box2f", 16},
                                                                        {"v2i", 8},
                                                                        {"v2f", 8},
                                                                        {"v2d", 16},
                                                                        {"v3i", 12},
                                                                        {"v3f", 12},
                                                                        {"v3d", 24},
                                                                        {"m33f", 36},
                                                                        {"m33d", 72},
                                                                        {"m44f", 64},
                                                                        {"m44d", 128},
                                                                        {"int", 4},
                                                                        {"float", 4},
                                                                        {"double", 8},
                                                                        {"compression", 1},
                                                                        {"lineOrder", 1},
                                                                        {"envmap", 1},
                                                                        {"deepImageState", 1},
                                                                        {"rational", 8},
                                                                        {"timecode", 8},
                                                                        {"keycode", 28},
                                                                        {"chromaticities", 32},
                                                                        {"tiledesc", 9}};
  for (const auto& [name, size] : kFixed) {
    if (type == name) return size;
  }
  return std::nullopt;
}

std::int64_t signed32(std::span<const std::uint8_t> v, std::size_t at) {
  return static_cast<std::int32_t>(little_endian32(v.data() + at));
}

// A channel list: entries of a name, NUL and 16 bytes, up to an empty name. How many channels it holds, and
// what is wrong when it does not end exactly at its declared size (OpenEXR reads it up to its terminator).
struct ChannelList {
  std::int64_t channels = 0;
  std::optional<std::string> problem;
};

ChannelList channel_list(std::span<const std::uint8_t> v) {
  ChannelList list;
  std::size_t at = 0;
  while (at < v.size() && v[at] != 0) {
    const auto nul = std::find(v.begin() + static_cast<std::ptrdiff_t>(at), v.end(), 0);
    at = static_cast<std::size_t>(nul - v.begin()) + 1 + 16;
    if (nul == v.end() || at > v.size()) {
      list.problem = "a channel runs past the attribute's size";
      return list;
    }
    ++list.channels;
  }
  if (at + 1 != v.size()) list.problem = "the channel list does not end at the attribute's size";
  return list;
}

// Why the value `v` (its declared size) of an attribute of type `type` is not what OpenEXR would read in that
// many bytes: the types OpenEXR reads with sizes of their own (a channel list up to its terminator, a string
// vector's strings, a preview's pixels, which it allocates at the size they claim) must end exactly where the
// declared size does. Other types are read at the declared size (a string, an unknown type's opaque bytes).
std::optional<std::string> value_problem(const std::string& type, std::span<const std::uint8_t> v) {
  if (const std::optional<std::size_t> fixed = fixed_size(type)) {
    if (v.size() == *fixed) return std::nullopt;
    return "size " + std::to_string(v.size()) + ", not " + std::to_string(*fixed);
  }
  if (type == "chlist") return channel_list(v).problem;
  if (type == "stringvector") {  // strings of a 4-byte length and that many bytes, up to the size
    std::size_t at = 0;
    while (at < v.size()) {
      if (at + 4 > v.size()) return std::string("a string's length runs past the attribute's size");
      const std::int64_t length = signed32(v, at);
      at += 4;
      if (length < 0 || static_cast<std::uint64_t>(length) > v.size() - at) {
        return "a string claims " + std::to_string(length) + " bytes, more than the attribute holds";
      }
      at += static_cast<std::size_t>(length);
    }
    return std::nullopt;
  }
  if (type == "preview") {  // width, height, then 4 bytes a pixel
    if (v.size() < 8) return std::string("too short for a preview's size");
    const std::uint64_t width = little_endian32(v.data()), height = little_endian32(v.data() + 4);
    const std::uint64_t pixels = width * height;  // each factor below 2^32: no overflow
    if (pixels > v.size() / 4 || pixels * 4 + 8 != v.size()) {
      return "a preview of " + std::to_string(width) + " x " + std::to_string(height) + " px in " +
             std::to_string(v.size()) + " bytes";
    }
    return std::nullopt;
  }
  return std::nullopt;
}

// OpenEXR allocates its line buffers for the data window and the channels when it opens a file, before the
// reader can look at the image's size: an image larger than the limits is refused here, as the reader would
// refuse it after opening.
std::optional<std::string> beyond_limits(const std::string& attribute, const std::string& type,
                                         std::span<const std::uint8_t> v, const ImageLimits& limits) {
  if (attribute == "dataWindow" && type == "box2i") {
    const std::int64_t width = signed32(v, 8) - signed32(v, 0) + 1, height = signed32(v, 12) - signed32(v, 4) + 1;
    const std::string size = std::to_string(width) + " x " + std::to_string(height) + " px";
    if (width <= 0 || height <= 0) return "image has zero size (data window " + size + ")";
    if (width > limits.max_side || height > limits.max_side) {
      return "image is " + size + ", more than the limit of " + std::to_string(limits.max_side) + " px per side";
    }
    if (width * height > limits.max_pixels) {
      return "image is " + size + ", more than the limit of " + std::to_string(limits.max_pixels) + " pixels";
    }
  }
  if (type == "chlist") {
    const std::int64_t channels = channel_list(v).channels;
    if (channels > limits.max_channels) {
      return "image has " + std::to_string(channels) + " channels, more than the limit of " +
             std::to_string(limits.max_channels);
    }
  }
  return std::nullopt;
}

// One header: attributes up to an empty name. Nothing when it is sound or `head` ends before it does
// (`unchecked` is then set).
std::optional<std::string> header_problem(HeaderWalk& walk, const ImageLimits& limits, bool& unchecked) {
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
    if (!walk.shown(static_cast<std::size_t>(size))) return cut_off();
    const std::span<const std::uint8_t> value = walk.bytes(static_cast<std::size_t>(size));
    if (std::optional<std::string> problem = value_problem(*type, value)) {
      return "attribute '" + *attribute + "' of type " + *type + ": " + *problem;
    }
    if (std::optional<std::string> problem = beyond_limits(*attribute, *type, value, limits)) return problem;
    walk.skip(static_cast<std::uint64_t>(size));
  }
}

}  // namespace

std::optional<std::string> exr_header_problem(std::span<const std::uint8_t> head, std::uint64_t file_size,
                                              const ImageLimits& limits) {
  if (head.size() < 8 || !std::equal(std::begin(kMagic), std::end(kMagic), head.begin())) {
    return file_size < 8 ? "too short for an OpenEXR file" : "not an OpenEXR file (no magic number)";
  }
  const bool multipart = (little_endian32(head.data() + 4) & kMultipartFlag) != 0;
  HeaderWalk walk(head, file_size);
  walk.skip(8);
  do {
    bool unchecked = false;
    if (std::optional<std::string> problem = header_problem(walk, limits, unchecked)) return problem;
    if (unchecked) return std::nullopt;
    // Multi-part files list headers up to an empty one.
  } while (multipart && walk.shown(1) && walk.byte() != 0);
  return std::nullopt;
}

void check_exr_header(const std::filesystem::path& path, const ImageLimits& limits) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return;  // the reader says why it cannot open it
  file.seekg(0, std::ios::end);
  const std::streamoff size = file.tellg();
  if (size < 0) return;
  file.seekg(0);
  std::vector<std::uint8_t> head(std::min<std::uint64_t>(static_cast<std::uint64_t>(size), kHeadBytes));
  file.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(file.gcount()));
  if (std::optional<std::string> problem = exr_header_problem(head, static_cast<std::uint64_t>(size), limits)) {
    throw FieldError(path.string() + ": " + *problem);
  }
}

}  // namespace ph
