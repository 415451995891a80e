#include "config/image_wire.hpp"
#include "config/write_all.hpp"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <optional>
#include <type_traits>

namespace ph::image_wire {
namespace {

enum class Tag : std::uint8_t { fields_request = 1, size_request, fields_answer, size_answer, failure };

class Writer {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const std::byte*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put_string(const std::string& text) {
    put<std::uint64_t>(text.size());
    const auto* p = reinterpret_cast<const std::byte*>(text.data());
    bytes_.insert(bytes_.end(), p, p + text.size());
  }
  void put_path(const std::optional<std::filesystem::path>& path) {
    put<std::uint8_t>(path ? 1 : 0);
    if (path) put_string(path->string());
  }
  template <typename T>
  void put_grid(const std::optional<Grid<T>>& grid) {
    put<std::uint8_t>(grid ? 1 : 0);
    if (!grid) return;
    put(grid->width);
    put(grid->height);
    put<std::uint64_t>(grid->values.size());
    const auto* p = reinterpret_cast<const std::byte*>(grid->values.data());
    bytes_.insert(bytes_.end(), p, p + grid->values.size() * sizeof(T));
  }
  std::vector<std::byte> take() { return std::move(bytes_); }

 private:
  std::vector<std::byte> bytes_;
};

class Reader {
 public:
  explicit Reader(const std::vector<std::byte>& bytes) : bytes_(bytes) {}
  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  bool get_flag() {
    const auto flag = get<std::uint8_t>();
    if (flag > 1) throw WireError("a flag that is neither 0 nor 1");
    return flag == 1;
  }
  std::string get_string() {
    const auto size = get<std::uint64_t>();
    const std::byte* p = take(size);
    return {reinterpret_cast<const char*>(p), static_cast<std::size_t>(size)};
  }
  std::optional<std::filesystem::path> get_path() {
    if (!get_flag()) return std::nullopt;
    return std::filesystem::path(get_string());
  }
  template <typename T>
  std::optional<Grid<T>> get_grid() {
    if (!get_flag()) return std::nullopt;
    Grid<T> grid;
    grid.width = get<std::int32_t>();
    grid.height = get<std::int32_t>();
    const auto count = get<std::uint64_t>();
    if (grid.width <= 0 || grid.height <= 0 ||
        count != static_cast<std::uint64_t>(grid.width) * static_cast<std::uint64_t>(grid.height) ||
        count > kMaxMessage / sizeof(T))
      throw WireError("a field whose size does not match its values");
    const std::byte* p = take(count * sizeof(T));
    grid.values.resize(static_cast<std::size_t>(count));
    std::memcpy(grid.values.data(), p, static_cast<std::size_t>(count) * sizeof(T));
    return grid;
  }
  void finish() const {
    if (at_ != bytes_.size()) throw WireError("bytes left over after the message");
  }

 private:
  const std::byte* take(std::uint64_t n) {
    if (n > bytes_.size() - at_) throw WireError("a message cut short");
    const std::byte* p = bytes_.data() + at_;
    at_ += static_cast<std::size_t>(n);
    return p;
  }
  const std::vector<std::byte>& bytes_;
  std::size_t at_ = 0;
};

// The enums and option structs cross as they are in memory; the values are checked on arrival.
static_assert(std::is_trivially_copyable_v<NormalDecodeOptions> && std::is_trivially_copyable_v<DepthDecodeOptions> &&
              std::is_trivially_copyable_v<FieldNeeds> && std::is_trivially_copyable_v<FieldLoadReport> &&
              std::is_trivially_copyable_v<ImageSize> && std::is_trivially_copyable_v<Gradient>);

// What the child loads crosses member by member (encode, decode_answer, and check_finite_grids for the values): the
// gradient, the heights and the two roundings; the discontinuity marks, the fusion's weight, the slope comparison and
// the smoothing's counts are made after, by the method. A member added to RegionFields changes its size and stops the
// build here until it is carried too (or the comment says why not).
static_assert(sizeof(RegionFields) == 240, "RegionFields changed: carry its new member on the image wire");
// What a region asks for crosses flag by flag: a member added to FieldNeeds stops the build here until it crosses too
// (depth_if_given once did not, and the daemon's hybrid regions got no depth map).
static_assert(sizeof(FieldNeeds) == 3, "FieldNeeds changed: carry its new member on the image wire");

void check_finite_grids(const RegionFields& fields) {
  // The sigmas of the slopes' and the heights' rounding: a hostile child's NaN, infinity or negative sigma stops here.
  for (double sigma : {fields.gradient_rounding, fields.depth_rounding}) {
    if (!(sigma >= 0.0 && std::isfinite(sigma))) throw WireError("a rounding that is not a finite sigma");
  }
  if (fields.gradient) {
    for (const Gradient& g : fields.gradient->values) {
      if (!(std::abs(g.x) <= kMaxSlope && std::abs(g.y) <= kMaxSlope)) throw WireError("a slope out of range");
    }
  }
  if (fields.depth) {
    for (float h : fields.depth->values) {
      if (!std::isfinite(h)) throw WireError("a height that is not finite");
    }
  }
}

}  // namespace

std::vector<std::byte> encode(const Request& request) {
  Writer w;
  if (const auto* f = std::get_if<FieldsRequest>(&request)) {
    w.put(Tag::fields_request);
    w.put_path(f->sources.normal_map);
    w.put(f->sources.normal_options);
    w.put_path(f->sources.depth_map);
    w.put(f->sources.depth_options);
    w.put(f->width);
    w.put(f->height);
    w.put<std::uint8_t>(f->needs.gradient ? 1 : 0);
    w.put<std::uint8_t>(f->needs.depth ? 1 : 0);
    w.put<std::uint8_t>(f->needs.depth_if_given ? 1 : 0);
  } else {
    w.put(Tag::size_request);
    w.put_string(std::get<SizeRequest>(request).path.string());
  }
  return w.take();
}

Request decode_request(const std::vector<std::byte>& bytes) {
  Reader r(bytes);
  const auto tag = r.get<Tag>();
  if (tag == Tag::fields_request) {
    FieldsRequest f;
    f.sources.normal_map = r.get_path();
    f.sources.normal_options = r.get<NormalDecodeOptions>();
    f.sources.depth_map = r.get_path();
    f.sources.depth_options = r.get<DepthDecodeOptions>();
    f.width = r.get<std::int32_t>();
    f.height = r.get<std::int32_t>();
    f.needs.gradient = r.get_flag();
    f.needs.depth = r.get_flag();
    f.needs.depth_if_given = r.get_flag();
    r.finish();
    return f;
  }
  if (tag == Tag::size_request) {
    SizeRequest s{r.get_string()};
    r.finish();
    return s;
  }
  throw WireError("an unknown request");
}

std::vector<std::byte> encode(const Answer& answer) {
  Writer w;
  if (const auto* f = std::get_if<FieldsAnswer>(&answer)) {
    w.put(Tag::fields_answer);
    w.put(f->report);
    w.put_grid(f->fields.gradient);
    w.put_grid(f->fields.depth);
    w.put(f->fields.gradient_rounding);
    w.put(f->fields.depth_rounding);
  } else if (const auto* s = std::get_if<ImageSize>(&answer)) {
    w.put(Tag::size_answer);
    w.put(*s);
  } else {
    w.put(Tag::failure);
    w.put_string(std::get<Failure>(answer).message);
  }
  return w.take();
}

Answer decode_answer(const std::vector<std::byte>& bytes, const Request& request) {
  Reader r(bytes);
  const auto tag = r.get<Tag>();
  if (tag == Tag::failure) {
    Failure failure{r.get_string()};
    r.finish();
    return failure;
  }
  if (const auto* f = std::get_if<FieldsRequest>(&request)) {
    if (tag != Tag::fields_answer) throw WireError("an answer of another kind than the request");
    FieldsAnswer a;
    a.report = r.get<FieldLoadReport>();
    a.fields.gradient = r.get_grid<Gradient>();
    a.fields.depth = r.get_grid<float>();
    a.fields.gradient_rounding = r.get<double>();
    a.fields.depth_rounding = r.get<double>();
    r.finish();
    auto fits = [&](const auto& grid, bool needed) {
      return grid.has_value() == needed && (!grid || (grid->width == f->width && grid->height == f->height));
    };
    // The heights where they were asked for, as load_region_fields reads them.
    if (!fits(a.fields.gradient, f->needs.gradient) ||
        !fits(a.fields.depth, f->needs.reads_depth(f->sources.depth_map.has_value())))
      throw WireError("fields other than those asked for");
    check_finite_grids(a.fields);
    return a;
  }
  if (tag != Tag::size_answer) throw WireError("an answer of another kind than the request");
  const auto size = r.get<ImageSize>();
  r.finish();
  return size;
}

void write_message(int fd, const std::vector<std::byte>& bytes) {
  const std::uint64_t size = bytes.size();
  if (!write_all(fd, &size, sizeof size) || !write_all(fd, bytes.data(), bytes.size()))
    throw WireError(std::string("cannot write to the image reader's pipe: ") + std::strerror(errno));
}

bool read_message(int fd, std::vector<std::byte>& bytes,
                  std::optional<std::chrono::steady_clock::time_point> deadline) {
  // Waits until fd is readable, or throws once the deadline has passed.
  auto wait = [&] {
    if (!deadline) return;
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) throw WireError("a message not complete in time");
      pollfd p{fd, POLLIN, 0};
      const int n = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 60'000)));
      if (n > 0) return;
      if (n < 0 && errno != EINTR) throw WireError(std::string("cannot wait for the pipe: ") + std::strerror(errno));
    }
  };
  // Reads n bytes; returns how many came before end of file.
  auto read_all = [&](void* data, std::size_t n) {
    auto* p = static_cast<char*>(data);
    std::size_t got = 0;
    while (got < n) {
      wait();
      const ssize_t done = ::read(fd, p + got, n - got);
      if (done < 0 && errno == EINTR) continue;
      if (done < 0) throw WireError(std::string("cannot read the image reader's pipe: ") + std::strerror(errno));
      if (done == 0) break;
      got += static_cast<std::size_t>(done);
    }
    return got;
  };
  std::uint64_t size = 0;
  const std::size_t got = read_all(&size, sizeof size);
  if (got == 0) return false;
  if (got < sizeof size) throw WireError("a message cut short");
  if (size > kMaxMessage) throw WireError("a message larger than " + std::to_string(kMaxMessage) + " bytes");
  bytes.resize(static_cast<std::size_t>(size));
  if (read_all(bytes.data(), bytes.size()) < bytes.size()) throw WireError("a message cut short");
  return true;
}

}  // namespace ph::image_wire
