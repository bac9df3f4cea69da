#include "scene/environment.h"

#include "core/log.h"

#include <IexBaseExc.h>
#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfRgbaFile.h>
#include <stb_image.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>
#include <tuple>

namespace wt {
namespace {

constexpr double kPi = std::numbers::pi;

double luminance709(const WtVec4& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

[[noreturn]] void fail(const std::string& name, const std::string& what) {
  throw EnvironmentError(name + ": " + what);
}

/// Text from a file as it can appear in a message: at most 64 characters,
/// bytes outside printable ASCII as \xNN.
std::string printable(std::string_view text) {
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < 64; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) out += char(c);
    else out += std::string("\\x") + kHex[c >> 4] + kHex[c & 15];
  }
  return text.size() > 64 ? out + "..." : out;
}

/// Maps of this many texels or more are refused (the sampling tables index
/// them with 32-bit integers).
constexpr std::int64_t kMaxTexels = std::int64_t(1) << 31;

void checkMapSize(const std::string& name, std::int64_t width, std::int64_t height) {
  if (width >= kMaxTexels || height >= kMaxTexels || width * height >= kMaxTexels)
    fail(name, "map too large (" + std::to_string(width) + " x " + std::to_string(height) + ")");
}

std::vector<unsigned char> readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path.string(), std::string("cannot open: ") + std::strerror(errno));
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) fail(path.string(), "read error");
  return bytes;
}

// ---------------------------------------------------------------------------
// Radiance .hdr

// stb_image 2.27 does not notice truncated run-length data (it reads zeros,
// and loops forever on a zero run count), so the structure is walked here
// before stb decodes it. The header is read as stb reads it, or the two
// could disagree on where the pixels start (found by fuzz_hdr: a line
// starting with NUL ends stb's header, not a naive one): a line is its bytes
// up to '\n', as a C string, at most 1023 characters. Returns the size.
std::pair<int, int> checkRadianceFile(const std::string& name, std::span<const unsigned char> bytes) {
  constexpr std::size_t kStbLineLength = 1023;  // STBI__HDR_BUFLEN - 1
  std::size_t pos = 0;
  auto nextLine = [&]() -> std::optional<std::string> {
    auto end = std::find(bytes.begin() + std::ptrdiff_t(pos), bytes.end(), '\n');
    if (end == bytes.end()) return std::nullopt;
    auto stop = std::find(bytes.begin() + std::ptrdiff_t(pos), end, '\0');
    std::string text(bytes.begin() + std::ptrdiff_t(pos), stop);
    if (text.size() > kStbLineLength) text.resize(kStbLineLength);
    pos = std::size_t(end - bytes.begin()) + 1;
    return text;
  };
  std::optional<std::string> line = nextLine();
  if (!line && bytes.size() >= 2 && bytes[0] == '#' && bytes[1] == '?') fail(name, "truncated: the header has no end");
  if (!line || (*line != "#?RADIANCE" && *line != "#?RGBE"))
    fail(name, "not a Radiance HDR file (no #?RADIANCE or #?RGBE first line)");
  bool rgbe = false;
  for (;;) {
    line = nextLine();
    if (!line) fail(name, "truncated: the header has no end");
    if (line->empty()) break;
    if (*line == "FORMAT=32-bit_rle_rgbe") rgbe = true;
    else if (line->rfind("FORMAT=", 0) == 0)
      fail(name, "unsupported pixel format '" + printable(line->substr(7)) + "' (only 32-bit_rle_rgbe)");
  }
  if (!rgbe) fail(name, "no FORMAT=32-bit_rle_rgbe line in the header");
  // "-Y height +X width", parsed as stb parses it, but every field required
  line = nextLine();
  auto badResolution = [&] {
    fail(name, "unsupported resolution line '" + printable(line.value_or("")) + "' (only '-Y height +X width')");
  };
  if (!line || line->rfind("-Y ", 0) != 0) badResolution();
  const char* text = line->c_str() + 3;
  char* end = nullptr;
  errno = 0;
  const long height = std::strtol(text, &end, 10);
  if (end == text || errno == ERANGE) badResolution();
  while (*end == ' ') ++end;
  if (std::strncmp(end, "+X ", 3) != 0) badResolution();
  text = end + 3;
  errno = 0;
  const long width = std::strtol(text, &end, 10);
  if (end == text || errno == ERANGE) badResolution();
  for (; *end != '\0'; ++end)
    if (!std::isspace(static_cast<unsigned char>(*end))) badResolution();
  if (width <= 0 || height <= 0 || width > (1 << 24) || height > (1 << 24))
    fail(name, "bad image size " + std::to_string(width) + " x " + std::to_string(height));

  const std::size_t w = std::size_t(width), h = std::size_t(height);
  auto need = [&](std::size_t n, std::size_t row) {
    if (bytes.size() - pos < n)
      fail(name, "truncated: scanline " + std::to_string(row) + " of " + std::to_string(h) + " ends early (file has " +
                     std::to_string(bytes.size()) + " bytes)");
  };
  const std::size_t flatBytes = w * h * 4;
  const std::pair<int, int> size{int(width), int(height)};
  if (w < 8 || w >= 32768) {
    need(flatBytes, 0);  // flat pixels only
    return size;
  }
  for (std::size_t row = 0; row < h; ++row) {
    need(4, row);
    const unsigned char* s = bytes.data() + pos;
    if (s[0] != 2 || s[1] != 2 || (s[2] & 0x80)) {
      if (row != 0) fail(name, "scanline " + std::to_string(row) + " is not run-length encoded but earlier ones are");
      need(flatBytes, row);
      return size;
    }
    std::size_t length = (std::size_t(s[2]) << 8) | s[3];
    if (length != w) fail(name, "scanline " + std::to_string(row) + " has length " + std::to_string(length) + ", expected " + std::to_string(w));
    pos += 4;
    for (int channel = 0; channel < 4; ++channel) {
      for (std::size_t x = 0; x < w;) {
        need(1, row);
        unsigned count = bytes[pos++];
        if (count > 128) {
          count -= 128;
          need(1, row);
          ++pos;
        } else {
          if (count == 0) fail(name, "scanline " + std::to_string(row) + ": zero-length run");
          need(count, row);
          pos += count;
        }
        if (count > w - x) fail(name, "scanline " + std::to_string(row) + ": run past the end of the line");
        x += count;
      }
    }
  }
  return size;
}

std::vector<glm::vec3> readHdr(const std::string& name, std::span<const unsigned char> bytes, int& width,
                               int& height) {
  if (bytes.size() > std::size_t(std::numeric_limits<int>::max()))
    fail(name, "file too large for the .hdr reader (" + std::to_string(bytes.size()) + " bytes)");
  const auto [checkedWidth, checkedHeight] = checkRadianceFile(name, bytes);
  // stb must see the image the check walked, or the check proved nothing
  int channels = 0;
  if (!stbi_info_from_memory(bytes.data(), int(bytes.size()), &width, &height, &channels) ||
      width != checkedWidth || height != checkedHeight)
    fail(name, "ambiguous header: stb_image reads it differently from the structure check");
  std::unique_ptr<float, void (*)(void*)> pixels(
      stbi_loadf_from_memory(bytes.data(), int(bytes.size()), &width, &height, &channels, 3), stbi_image_free);
  if (!pixels) fail(name, std::string("cannot decode: ") + stbi_failure_reason());
  if (width != checkedWidth || height != checkedHeight) fail(name, "stb_image decoded an unexpected size");
  std::vector<glm::vec3> rgb(std::size_t(width) * std::size_t(height));
  std::memcpy(rgb.data(), pixels.get(), rgb.size() * sizeof(glm::vec3));
  return rgb;
}

// ---------------------------------------------------------------------------
// OpenEXR

/// A file's bytes as an OpenEXR input stream, so files and memory take one
/// path. Not memory-mapped on purpose: OpenEXR 3.1 then decodes chunks in
/// place and reads past a short uncompressed chunk, out of the buffer (found
/// by fuzz_exr); read() copies into OpenEXR's own full-size line buffers.
class MemoryIStream final : public Imf::IStream {
 public:
  MemoryIStream(const std::string& name, std::span<const unsigned char> bytes)
      : Imf::IStream(name.c_str()), m_bytes(bytes) {}

  bool read(char c[], int n) override {
    if (n < 0 || m_pos > m_bytes.size() || std::uint64_t(n) > m_bytes.size() - m_pos)
      throw Iex::InputExc("unexpected end of file: " + std::to_string(n) + " bytes requested at offset " +
                          std::to_string(m_pos) + " of " + std::to_string(m_bytes.size()));
    std::memcpy(c, m_bytes.data() + m_pos, std::size_t(n));
    m_pos += std::uint64_t(n);
    return m_pos < m_bytes.size();
  }
  std::uint64_t tellg() override { return m_pos; }
  void seekg(std::uint64_t pos) override { m_pos = pos; }  // past the end: the next read throws

 private:
  std::span<const unsigned char> m_bytes;
  std::uint64_t m_pos = 0;
};

std::uint32_t readU32(const unsigned char* p) {
  std::uint32_t v;  // OpenEXR is little-endian, and so is every machine we build for
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// Why an OpenEXR header attribute's value cannot be what its type reads, or
/// empty when it can. OpenEXR 3.1 reads fixed-size types at their own size
/// and channel lists up to their terminator, whatever size the file gives.
std::string exrAttributeProblem(const std::string& type, std::span<const unsigned char> value) {
  static const std::pair<const char*, std::size_t> kFixedSizes[] = {
      {"box2i", 16}, {"box2f", 16},    {"chromaticities", 32}, {"compression", 1}, {"deepImageState", 1},
      {"double", 8}, {"envmap", 1},    {"float", 4},           {"int", 4},         {"keycode", 28},
      {"lineOrder", 1}, {"m33f", 36},  {"m33d", 72},           {"m44f", 64},       {"m44d", 128},
      {"rational", 8}, {"tiledesc", 9}, {"timecode", 8},       {"v2i", 8},         {"v2f", 8},
      {"v2d", 16},   {"v3i", 12},      {"v3f", 12},            {"v3d", 24}};
  const std::size_t size = value.size();
  for (const auto& [fixedType, fixedSize] : kFixedSizes)
    if (type == fixedType)
      return size == fixedSize ? "" : "has " + std::to_string(size) + " bytes, expected " + std::to_string(fixedSize);
  if (type == "chlist") {
    // entries of name, NUL, 16 bytes; an empty name ends the list
    for (std::size_t pos = 0;;) {
      auto end = std::find(value.begin() + std::ptrdiff_t(pos), value.end(), '\0');
      if (end == value.end()) return "is not terminated within its " + std::to_string(size) + " bytes";
      const bool last = end == value.begin() + std::ptrdiff_t(pos);
      pos = std::size_t(end - value.begin()) + 1;
      if (last) return pos == size ? "" : "ends after " + std::to_string(pos) + " of its " + std::to_string(size) + " bytes";
      if (size - pos < 16) return "has a truncated channel entry";
      pos += 16;
    }
  }
  if (type == "stringvector") {
    // strings of a 4-byte length and that many bytes, filling the value
    for (std::size_t pos = 0; pos < size;) {
      if (size - pos < 4) return "has a truncated string length";
      const std::int32_t length = std::int32_t(readU32(value.data() + pos));
      pos += 4;
      if (length < 0 || std::size_t(length) > size - pos)
        return "has a string of " + std::to_string(length) + " bytes where " + std::to_string(size - pos) + " remain";
      pos += std::size_t(length);
    }
    return "";
  }
  if (type == "preview") {
    // width, height, then 4 bytes per pixel
    if (size < 8) return "has " + std::to_string(size) + " bytes, too few for a preview";
    const std::uint64_t pixels = std::uint64_t(readU32(value.data())) * readU32(value.data() + 4);
    return pixels * 4 + 8 == size ? "" : "has " + std::to_string(size) + " bytes for a preview of " +
                                             std::to_string(pixels) + " pixels";
  }
  if (type == "floatvector" && size % 4 != 0)
    return "has " + std::to_string(size) + " bytes, not a whole number of floats";
  return "";
}

/// The data window of a file of `fileSize` bytes, checked before anything
/// is allocated for it (by OpenEXR, whose line buffers follow the window, or
/// by us). A file cannot hold more texels than its compression packs into
/// its bytes: deflate (ZIP, PXR24) packs at most 1032 bytes into one, i.e.
/// 516 half texels, the others less, except DWA, which stores a constant
/// 8 x 8 block as one deflated value (64 x 1032 / 2 texels per byte).
/// Returns width and height.
std::pair<int, int> checkDataWindow(const std::string& name, const Imath::Box2i& window, int compression,
                                    std::size_t fileSize) {
  const bool dwa = compression == Imf::DWAA_COMPRESSION || compression == Imf::DWAB_COMPRESSION;
  const std::int64_t maxTexelsPerByte = dwa ? 33024 : 1024;
  // in 64 bits: a corrupt window can span more than an int
  const std::int64_t width = std::int64_t(window.max.x) - window.min.x + 1;
  const std::int64_t height = std::int64_t(window.max.y) - window.min.y + 1;
  if (width <= 0 || height <= 0) fail(name, "empty data window");
  checkMapSize(name, width, height);
  if (width * height / maxTexelsPerByte > std::int64_t(fileSize))
    fail(name, "corrupt header: a " + std::to_string(width) + " x " + std::to_string(height) +
                   " data window cannot fit in " + std::to_string(fileSize) + " bytes");
  return {int(width), int(height)};
}

/// Tiles may be larger than the data window (a 64 x 64 tile on a 50-row
/// image), but OpenEXR allocates a tile, and a row of tiles across the
/// window, before reading any: a tile much larger than the window is refused.
void checkTileSize(const std::string& name, const Imath::Box2i& window, std::uint32_t tileWidth,
                   std::uint32_t tileHeight) {
  constexpr std::int64_t kSlack = 256;
  const std::int64_t width = std::int64_t(window.max.x) - window.min.x + 1;
  const std::int64_t height = std::int64_t(window.max.y) - window.min.y + 1;
  if (tileWidth == 0 || tileHeight == 0 || tileWidth > std::max(width, kSlack) || tileHeight > std::max(height, kSlack))
    fail(name, "corrupt header: " + std::to_string(tileWidth) + " x " + std::to_string(tileHeight) +
                   " tiles for a " + std::to_string(width) + " x " + std::to_string(height) + " data window");
}

// OpenEXR 3.1 allocates each header attribute at the size the file claims
// (up to 2 GiB, zero-filled for strings) before it finds the file shorter,
// and where a value's declared size disagrees with what its type reads, it
// reads the rest of the header out of step and allocates for whatever it
// finds there. So a corrupt 100-byte file could take gigabytes; the header
// structure is checked here first, everything else is left to OpenEXR.
void checkExrHeaders(const std::string& name, std::span<const unsigned char> bytes) {
  constexpr std::uint32_t kMagic = 20000630;
  constexpr std::uint32_t kMultiPart = 0x1000;
  if (bytes.size() < 8 || readU32(bytes.data()) != kMagic) return;  // OpenEXR says what it is not
  const bool multiPart = (readU32(bytes.data() + 4) & kMultiPart) != 0;
  std::size_t pos = 8;
  auto text = [&]() -> std::optional<std::string> {
    auto end = std::find(bytes.begin() + std::ptrdiff_t(pos), bytes.end(), '\0');
    if (end == bytes.end()) return std::nullopt;
    std::string s(bytes.begin() + std::ptrdiff_t(pos), end);
    pos = std::size_t(end - bytes.begin()) + 1;
    return s;
  };
  for (;;) {  // headers: one, or for multi-part files a list ended by an empty one
    if (multiPart && pos < bytes.size() && bytes[pos] == 0) return;
    std::optional<Imath::Box2i> window;
    std::optional<std::pair<std::uint32_t, std::uint32_t>> tile;
    int compression = Imf::ZIP_COMPRESSION;  // OpenEXR's default when the attribute is absent
    for (;;) {  // attributes: name, type, size, value; an empty name ends the header
      std::optional<std::string> attribute = text();
      if (!attribute) return;  // truncated: OpenEXR reports it
      if (attribute->empty()) break;
      std::optional<std::string> type = text();
      if (!type || bytes.size() - pos < 4) return;
      const std::int32_t size = std::int32_t(readU32(bytes.data() + pos));
      pos += 4;
      const std::string label = "cannot read OpenEXR file: header attribute '" + printable(*attribute) +
                                "' of type '" + printable(*type) + "' ";
      if (size < 0 || std::size_t(size) > bytes.size() - pos)
        fail(name, label + "claims " + std::to_string(size) + " bytes, " + std::to_string(bytes.size() - pos) +
                       " follow");
      const std::string problem = exrAttributeProblem(*type, bytes.subspan(pos, std::size_t(size)));
      if (!problem.empty()) fail(name, label + problem);
      // sizes are right here: what OpenEXR sizes its buffers by
      const unsigned char* v = bytes.data() + pos;
      const auto at = [&](int i) { return std::int32_t(readU32(v + 4 * i)); };
      if (*attribute == "dataWindow" && *type == "box2i") window = Imath::Box2i({at(0), at(1)}, {at(2), at(3)});
      if (*attribute == "tiles" && *type == "tiledesc") tile = std::pair(readU32(v), readU32(v + 4));
      if (*attribute == "compression" && *type == "compression") compression = v[0];
      pos += std::size_t(size);
    }
    if (!window) fail(name, "cannot read OpenEXR file: the header has no dataWindow");
    checkDataWindow(name, *window, compression, bytes.size());
    if (tile) checkTileSize(name, *window, tile->first, tile->second);
    if (!multiPart) return;
  }
}

std::vector<glm::vec3> readExrPixels(const std::string& name, std::span<const unsigned char> bytes, int& width,
                                     int& height) {
  checkExrHeaders(name, bytes);
  MemoryIStream stream(name, bytes);
  Imf::InputFile file(stream);
  const Imf::Header& header = file.header();
  const Imath::Box2i window = header.dataWindow();
  std::tie(width, height) = checkDataWindow(name, window, header.compression(), bytes.size());  // as checkExrHeaders did
  const std::size_t count = std::size_t(width) * std::size_t(height);
  // the texels are allocated before OpenEXR decodes them: every chunk must be there
  if (!file.isComplete()) fail(name, "truncated: some scanlines or tiles are missing");

  const Imf::ChannelList& channels = header.channels();
  auto has = [&](const char* c) { return channels.findChannel(c) != nullptr; };
  std::string names;
  for (auto it = channels.begin(); it != channels.end(); ++it)
    names += (names.empty() ? "" : ", ") + std::string(it.name());
  // R, G, B and Y are read at full resolution; RY and BY are sub-sampled by
  // design, and the RGBA interface reconstructs them
  auto fullResolution = [&](std::initializer_list<const char*> read) {
    for (const char* c : read) {
      const Imf::Channel& channel = *channels.findChannel(c);
      if (channel.xSampling != 1 || channel.ySampling != 1)
        fail(name, std::string("channel ") + c + " is sub-sampled (not supported)");
    }
  };

  std::vector<glm::vec3> rgb;
  if (has("R") && has("G") && has("B")) {
    fullResolution({"R", "G", "B"});
    rgb.resize(count);
    Imf::FrameBuffer fb;
    const std::size_t xs = sizeof(glm::vec3), ys = xs * std::size_t(width);
    fb.insert("R", Imf::Slice::Make(Imf::FLOAT, &rgb[0].x, window, xs, ys));
    fb.insert("G", Imf::Slice::Make(Imf::FLOAT, &rgb[0].y, window, xs, ys));
    fb.insert("B", Imf::Slice::Make(Imf::FLOAT, &rgb[0].z, window, xs, ys));
    file.setFrameBuffer(fb);
    file.readPixels(window.min.y, window.max.y);
  } else if (has("Y") && !has("RY") && !has("BY")) {
    fullResolution({"Y"});
    rgb.resize(count);
    std::vector<float> y(count);
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), window, sizeof(float), sizeof(float) * std::size_t(width)));
    file.setFrameBuffer(fb);
    file.readPixels(window.min.y, window.max.y);
    for (std::size_t i = 0; i < count; ++i) rgb[i] = glm::vec3(y[i]);
  } else if (has("Y")) {
    // luminance/chroma: the RGBA interface converts (at half precision)
    fullResolution({"Y"});
    rgb.resize(count);
    MemoryIStream rgbaStream(name, bytes);
    Imf::RgbaInputFile rgbaFile(rgbaStream);
    std::vector<Imf::Rgba> px(count);
    rgbaFile.setFrameBuffer(px.data() - window.min.x - std::ptrdiff_t(window.min.y) * width, 1, std::size_t(width));
    rgbaFile.readPixels(window.min.y, window.max.y);
    for (std::size_t i = 0; i < count; ++i) rgb[i] = glm::vec3(float(px[i].r), float(px[i].g), float(px[i].b));
  } else {
    fail(name, "unsupported channel layout (" + names + "): an environment map needs R, G and B, or Y channels");
  }
  return rgb;
}

std::vector<glm::vec3> readExr(const std::string& name, std::span<const unsigned char> bytes, int& width,
                               int& height) {
  try {
    return readExrPixels(name, bytes, width, height);
  } catch (const EnvironmentError&) {
    throw;
  } catch (const std::exception& e) {
    // OpenEXR's messages (unknown compression, truncated tiles, ...) as they are
    fail(name, std::string("cannot read OpenEXR file: ") + e.what());
  }
}

// ---------------------------------------------------------------------------
// distribution

// Rows weighted by luminance x sin(theta of the row centre), so the density
// in (u, v) is proportional to luminance per solid angle. Sums in double,
// cdfs normalised and stored as float with the last entry exactly 1.
void buildDistribution(Environment& env) {
  const std::size_t w = env.header.width, h = env.header.height;
  env.conditionalCdf.assign(h * (w + 1), 0.0f);
  env.marginalCdf.assign(h + 1, 0.0f);
  std::vector<double> rowPrefix(w + 1), marginalPrefix(h + 1, 0.0);
  double luminanceSolidAngle = 0.0;
  for (std::size_t j = 0; j < h; ++j) {
    const double theta0 = kPi * double(j) / double(h), theta1 = kPi * double(j + 1) / double(h);
    const double sinTheta = std::sin(0.5 * (theta0 + theta1));
    const double texelSolidAngle = 2.0 * kPi / double(w) * (std::cos(theta0) - std::cos(theta1));
    rowPrefix[0] = 0.0;
    for (std::size_t i = 0; i < w; ++i) {
      double lum = luminance709(env.texels[j * w + i]);
      rowPrefix[i + 1] = rowPrefix[i] + lum * sinTheta;
      luminanceSolidAngle += lum * texelSolidAngle;
    }
    float* row = &env.conditionalCdf[j * (w + 1)];
    const double sum = rowPrefix[w];
    for (std::size_t i = 0; i < w; ++i)
      row[i] = sum > 0.0 ? float(rowPrefix[i] / sum) : float(double(i) / double(w));  // black row: never chosen, kept finite
    row[w] = 1.0f;
    marginalPrefix[j + 1] = marginalPrefix[j] + sum;
  }
  const double total = marginalPrefix[h];
  for (std::size_t j = 0; j < h; ++j)
    env.marginalCdf[j] = total > 0.0 ? float(marginalPrefix[j] / total) : float(double(j) / double(h));
  env.marginalCdf[h] = 1.0f;
  env.header.mode = total > 0.0 ? WT_ENV_MAP : WT_ENV_MAP_UNIFORM;
  env.meanLuminance = double(env.header.intensity) * luminanceSolidAngle / (4.0 * kPi);
}

void setRotation(WtEnvironment& header, float rotationDegrees) {
  const double radians = double(rotationDegrees) * kPi / 180.0;
  header.rotation = float(radians);
  header.cos_rotation = float(std::cos(radians));
  header.sin_rotation = float(std::sin(radians));
}

void checkParameters(const std::string& name, float intensity, float rotationDegrees) {
  if (!std::isfinite(intensity) || intensity < 0.0f)
    fail(name, "intensity " + std::to_string(intensity) + " must be finite and >= 0");
  if (!std::isfinite(rotationDegrees)) fail(name, "rotation must be finite");
}

/// The lower-case extension of `name`, which must be .hdr or .exr.
std::string checkFormat(const std::string& name) {
  std::string ext = std::filesystem::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext != ".hdr" && ext != ".exr")
    fail(name, "unsupported environment map format '" + ext + "' (expected .hdr or .exr)");
  return ext;
}

}  // namespace

EnvironmentUpload environmentUpload(const Environment& environment) {
  return {environment.texels, environment.marginalCdf, environment.conditionalCdf};
}

Environment makeEnvironmentMap(int width, int height, std::vector<glm::vec3> rgb, float intensity,
                               float rotationDegrees, const std::string& sourceName) {
  checkParameters(sourceName, intensity, rotationDegrees);
  if (width <= 0 || height <= 0 || std::size_t(width) * std::size_t(height) != rgb.size())
    fail(sourceName, "bad map size " + std::to_string(width) + " x " + std::to_string(height) + " for " +
                         std::to_string(rgb.size()) + " pixels");
  checkMapSize(sourceName, width, height);

  Environment env;
  env.sourceName = sourceName;
  env.header.color = {0.0f, 0.0f, 0.0f, 0.0f};
  env.header.intensity = intensity;
  setRotation(env.header, rotationDegrees);
  env.header.width = wt_uint(width);
  env.header.height = wt_uint(height);

  // repair: negative and non-finite values become 0
  std::size_t repaired = 0;
  env.texels.resize(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    float c[3] = {rgb[i].x, rgb[i].y, rgb[i].z};
    for (float& v : c)
      if (!(std::isfinite(v) && v >= 0.0f)) {
        v = 0.0f;
        ++repaired;
      }
    env.texels[i] = {c[0], c[1], c[2], 0.0f};
  }
  if (repaired > 0) {
    env.warnings.push_back(sourceName + ": " + std::to_string(repaired) +
                           " texel values were negative or not finite; set to 0");
    log::warnOnce(env.warnings.back());
  }
  if (width != 2 * height) {
    env.warnings.push_back(sourceName + ": " + std::to_string(width) + " x " + std::to_string(height) +
                           " is not 2:1; stretched over the sphere as latitude-longitude");
    log::warnOnce(env.warnings.back());
  }
  buildDistribution(env);
  return env;
}

Environment loadEnvironmentMap(const std::filesystem::path& path, float intensity, float rotationDegrees) {
  const std::string name = path.string();
  checkParameters(name, intensity, rotationDegrees);
  if (!std::filesystem::exists(path)) fail(name, "no such file");
  checkFormat(name);
  const std::vector<unsigned char> bytes = readBytes(path);
  return loadEnvironmentMapFromMemory(bytes, name, intensity, rotationDegrees);
}

Environment loadEnvironmentMapFromMemory(std::span<const unsigned char> bytes, const std::string& name,
                                         float intensity, float rotationDegrees) {
  checkParameters(name, intensity, rotationDegrees);
  const std::string ext = checkFormat(name);
  int width = 0, height = 0;
  std::vector<glm::vec3> rgb =
      ext == ".hdr" ? readHdr(name, bytes, width, height) : readExr(name, bytes, width, height);
  return makeEnvironmentMap(width, height, std::move(rgb), intensity, rotationDegrees, name);
}

Environment constantEnvironment(glm::vec3 radiance) {
  Environment env;
  env.sourceName = "constant";
  env.header.color = {radiance.x, radiance.y, radiance.z, 0.0f};
  env.header.intensity = 1.0f;
  setRotation(env.header, 0.0f);
  env.header.mode = WT_ENV_CONSTANT;
  env.header.width = 1;
  env.header.height = 1;
  env.texels = {{0.0f, 0.0f, 0.0f, 0.0f}};
  env.marginalCdf = {0.0f, 1.0f};
  env.conditionalCdf = {0.0f, 1.0f};
  env.meanLuminance = luminance709(env.header.color);
  return env;
}

static_assert(sizeof(WtEnvironment) == 48, "WtEnvironment must match the OpenCL layout");

}  // namespace wt
