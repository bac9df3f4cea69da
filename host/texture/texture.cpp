#include "texture/texture.h"

#include <stb_image.h>

#include <algorithm>
#include <limits>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <memory>
#include <atomic>
#include <bit>
#include <exception>
#include <system_error>
#include <thread>
#include <future>

namespace wt {

static_assert(sizeof(WtTexture) == 16);
static_assert(sizeof(WtTextureLevel) == 16);

namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw TextureError(name + ": " + what); }

std::string stbReason() {
  const char* reason = stbi_failure_reason();
  return reason ? reason : "no reason given";
}

/// The first bytes of a file as hex, for a message about its format.
std::string firstBytes(const unsigned char* bytes, std::size_t size) {
  static const char* kHex = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < size && i < 8; ++i) {
    if (i) out += ' ';
    out += kHex[bytes[i] >> 4];
    out += kHex[bytes[i] & 15];
  }
  return out;
}

bool startsWith(const unsigned char* bytes, std::size_t size, std::size_t at, std::string_view magic) {
  return size >= at + magic.size() && std::memcmp(bytes + at, magic.data(), magic.size()) == 0;
}

void checkImageSize(const std::string& name, std::uint64_t width, std::uint64_t height) {
  if (width == 0 || height == 0)
    fail(name, "empty image (" + std::to_string(width) + " x " + std::to_string(height) + ")");
  if (width > kMaxTextureSide || height > kMaxTextureSide || width * height > kMaxTextureTexels)
    fail(name, "image too large (" + std::to_string(width) + " x " + std::to_string(height) + "; at most " +
                   std::to_string(kMaxTextureSide) + " per side and " + std::to_string(kMaxTextureTexels >> 20) +
                   " M texels)");
}

// ---------------------------------------------------------------------------
// JPEG Huffman tables

// stb_image 2.27 trusts a DHT table's code counts: counts summing past 256
// write past the table's arrays into the rest of its decoder state (2.28
// refuses them; UBSan reports it on mutated files). The file's marker
// segments are walked here as stb walks them and such tables refused first.
// Entropy-coded data is read byte by byte, so a marker stb would act on
// between scans (progressive files carry tables there) is seen too.
void checkJpegHuffmanTables(const std::string& name, const unsigned char* bytes, std::size_t size) {
  auto at = [&](std::size_t i) -> unsigned { return i < size ? bytes[i] : 0u; };  // stb reads 0 past the end
  std::size_t pos = 2;  // after SOI
  while (pos < size) {
    if (bytes[pos++] != 0xff) continue;
    while (pos < size && bytes[pos] == 0xff) ++pos;  // fill bytes
    if (pos >= size) return;
    const unsigned marker = bytes[pos++];
    if (marker == 0x00 || marker == 0x01 || (marker >= 0xd0 && marker <= 0xd8)) continue;  // no length
    if (marker == 0xd9) return;                                                           // EOI
    const std::size_t length = at(pos) << 8 | at(pos + 1);
    if (marker != 0xc4) {
      pos += length;  // a segment's length counts its own two bytes
      continue;
    }
    // DHT: tables until the length is used up, read on past it as stb does
    std::size_t p = pos + 2;
    long left = long(length) - 2;
    while (left > 0 && p < size) {
      if ((at(p) >> 4) > 1 || (at(p) & 15) > 3) return;  // stb refuses the file
      unsigned codes = 0;
      for (std::size_t i = 1; i <= 16; ++i) codes += at(p + i);
      if (codes > 256)
        fail(name, "cannot decode the JPEG data: a Huffman table has " + std::to_string(codes) +
                       " codes (at most 256): corrupt JPEG");
      p += 17 + codes;
      left -= long(17 + codes);
    }
    if (left != 0) return;  // stb refuses the file
    pos = p;
  }
}

// ---------------------------------------------------------------------------
// sRGB tables

struct Srgb8 {
  std::array<float, 256> toLinear;          ///< decoded value of each code
  std::array<double, 255> thresholds;       ///< code k + 1 from linear thresholds[k] up (midpoints in encoded space)
  std::array<std::uint8_t, 4097> guess;     ///< code of linear i / 4096, exact; a start for encodeSrgb8
};

const Srgb8& srgb8() {
  static const Srgb8 table = [] {
    Srgb8 t{};
    for (int i = 0; i < 256; ++i) t.toLinear[i] = float(srgbToLinear(i / 255.0));
    for (int k = 0; k < 255; ++k) t.thresholds[k] = srgbToLinear((k + 0.5) / 255.0);
    for (int i = 0; i <= 4096; ++i)
      t.guess[i] = std::uint8_t(std::upper_bound(t.thresholds.begin(), t.thresholds.end(), i / 4096.0) -
                                t.thresholds.begin());
    return t;
  }();
  return table;
}

/// round(255 x linearToSrgb(linear)) without pow: the code at the start of
/// linear's 1/4096 cell, stepped up past the thresholds below linear (one
/// step at most: no cell spans two codes, even near black where the curve
/// is steepest).
std::uint8_t encodeSrgb8(float linear) {
  const Srgb8& t = srgb8();
  const double x = std::clamp(double(linear), 0.0, 1.0);
  unsigned k = t.guess[unsigned(x * 4096.0)];
  while (k < 255 && x >= t.thresholds[k]) ++k;
  return std::uint8_t(k);
}

/// Decoded value of each 16-bit sRGB code (256 KiB, made on first use).
const std::vector<float>& srgb16ToLinear() {
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (std::size_t i = 0; i < t.size(); ++i) t[i] = float(srgbToLinear(double(i) / 65535.0));
    return t;
  }();
  return table;
}

// ---------------------------------------------------------------------------
// mip pyramid

/// The taps along one axis of a level n texels long for each texel of the
/// level below (max(n / 2, 1) texels): first source texel and weights.
struct Taps {
  std::uint32_t first = 0;
  std::uint32_t count = 1;
  float weight[3] = {1.0f, 0.0f, 0.0f};
};

std::vector<Taps> axisTaps(std::uint32_t n) {
  const std::uint32_t m = std::max(n / 2, 1u);
  std::vector<Taps> taps(m);
  if (n == 1) return taps;  // copied
  for (std::uint32_t x = 0; x < m; ++x) {
    Taps& t = taps[x];
    t.first = 2 * x;
    if (n % 2 == 0) {
      t.count = 2, t.weight[0] = t.weight[1] = 0.5f;
    } else {
      // footprint [x n / m, (x + 1) n / m) with n = 2m + 1 covers texels 2x .. 2x + 2
      t.count = 3;
      t.weight[0] = float(m - x) / float(n);
      t.weight[1] = float(m) / float(n);
      t.weight[2] = float(x + 1) / float(n);
    }
  }
  return taps;
}

/// How the channels of one storage type turn into values to filter and back.
struct Codec8 {
  bool srgb;
  /// `texels` RGBA texels to floats, linear light.
  void decodeRow(const std::uint8_t* in, float* out, std::size_t texels) const {
    const float* table = srgb8().toLinear.data();
    for (std::size_t i = 0; i < 4 * texels; i += 4) {
      for (int c = 0; c < 3; ++c) out[i + c] = srgb ? table[in[i + c]] : float(in[i + c]) * (1.0f / 255.0f);
      out[i + 3] = float(in[i + 3]) * (1.0f / 255.0f);
    }
  }
  std::uint8_t encode(float x, int channel) const {
    if (srgb && channel < 3) return encodeSrgb8(x);
    return std::uint8_t(std::clamp(x, 0.0f, 1.0f) * 255.0f + 0.5f);  // round to nearest
  }
};

struct Codec16 {
  bool srgb;
  void decodeRow(const std::uint16_t* in, float* out, std::size_t texels) const {
    const float* table = srgb ? srgb16ToLinear().data() : nullptr;
    for (std::size_t i = 0; i < 4 * texels; i += 4) {
      for (int c = 0; c < 3; ++c) out[i + c] = table ? table[in[i + c]] : float(in[i + c]) * (1.0f / 65535.0f);
      out[i + 3] = float(in[i + 3]) * (1.0f / 65535.0f);
    }
  }
  std::uint16_t encode(float x, int channel) const {
    double c = std::clamp(double(x), 0.0, 1.0);
    if (srgb && channel < 3) c = linearToSrgb(c);
    return std::uint16_t(c * 65535.0 + 0.5);
  }
};

/// The level below `src` (width x height RGBA) into `dst`, box-filtered per
/// the taps: each destination row blends its 1-3 source rows (decoded once
/// each), then its columns. `dst` is resized, so a caller's buffer is reused.
template <typename T, typename Codec>
void downsample(const T* src, std::uint32_t width, std::uint32_t height, const Codec& codec, std::vector<T>& dst) {
  const std::vector<Taps> tx = axisTaps(width), ty = axisTaps(height);
  const std::size_t rowValues = std::size_t(width) * 4;
  // rows 2y .. 2y + 2 of one destination row fall in distinct slots (row % 3)
  std::vector<float> decoded(3 * rowValues), blend(rowValues);
  std::array<std::int64_t, 3> slotRow = {-1, -1, -1};
  dst.resize(tx.size() * ty.size() * 4);
  std::size_t out = 0;
  for (const Taps& row : ty) {
    std::fill(blend.begin(), blend.end(), 0.0f);
    for (std::uint32_t j = 0; j < row.count; ++j) {
      const std::uint32_t r = row.first + j;
      float* line = decoded.data() + (r % 3) * rowValues;
      if (slotRow[r % 3] != r) codec.decodeRow(src + r * rowValues, line, width), slotRow[r % 3] = r;
      const float w = row.weight[j];
      for (std::size_t i = 0; i < rowValues; ++i) blend[i] += w * line[i];
    }
    for (const Taps& col : tx) {
      float sum[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      for (std::uint32_t i = 0; i < col.count; ++i)
        for (int c = 0; c < 4; ++c) sum[c] += col.weight[i] * blend[(col.first + i) * 4 + c];
      for (int c = 0; c < 4; ++c) dst[out++] = codec.encode(sum[c], c);
    }
  }
}

/// Pack `values` RGBA channel values at `out`: one uint per 8-bit texel
/// (r | g << 8 | b << 16 | a << 24), two per 16-bit texel (r | g << 16,
/// b | a << 16). On a little-endian host that is the channels' own bytes.
void packTexels(wt_uint* out, const std::uint8_t* rgba, std::size_t values) {
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(out, rgba, values);
  } else {
    for (std::size_t i = 0; i < values; i += 4)
      *out++ = wt_uint(rgba[i]) | wt_uint(rgba[i + 1]) << 8 | wt_uint(rgba[i + 2]) << 16 | wt_uint(rgba[i + 3]) << 24;
  }
}

void packTexels(wt_uint* out, const std::uint16_t* rgba, std::size_t values) {
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(out, rgba, values * sizeof(std::uint16_t));
  } else {
    for (std::size_t i = 0; i < values; i += 2) *out++ = wt_uint(rgba[i]) | wt_uint(rgba[i + 1]) << 16;
  }
}

/// Texel words of every level of a width x height image, level 0 first.
std::uint64_t pyramidWords(std::uint64_t w, std::uint64_t h, bool sixteenBit) {
  std::uint64_t total = 0;
  for (;; w = std::max<std::uint64_t>(w / 2, 1), h = std::max<std::uint64_t>(h / 2, 1)) {
    total += w * h * (sixteenBit ? 2 : 1);
    if (w == 1 && h == 1) return total;
  }
}

/// Write every level of an image, level 0 (`pixels`) first, packed at
/// `out` (pyramidWords of them), and append their level records with
/// offsets from `base`.
template <typename T, typename Codec>
void writePyramid(wt_uint* out, wt_uint base, std::vector<WtTextureLevel>& levels, const T* pixels,
                  std::uint32_t width, std::uint32_t height, const Codec& codec) {
  std::vector<T> buffers[2];  // the last level made and the one being made; level 0 is not copied
  const T* current = pixels;
  wt_uint offset = 0;
  for (int next = 0;; next ^= 1) {
    levels.push_back({base + offset, width, height, 0});
    const std::size_t values = std::size_t(width) * height * 4;
    packTexels(out + offset, current, values);
    offset += wt_uint(values * sizeof(T) / sizeof(wt_uint));
    if (width == 1 && height == 1) return;
    downsample(current, width, height, codec, buffers[next]);
    current = buffers[next].data();
    width = std::max(width / 2, 1u), height = std::max(height / 2, 1u);
  }
}

/// An image's pyramid into `out`: 8- or 16-bit, sRGB or linear.
void writePyramid(wt_uint* out, wt_uint base, std::vector<WtTextureLevel>& levels, const void* pixels,
                  std::uint32_t width, std::uint32_t height, bool sixteenBit, bool srgb) {
  if (sixteenBit)
    writePyramid(out, base, levels, static_cast<const std::uint16_t*>(pixels), width, height, Codec16{srgb});
  else
    writePyramid(out, base, levels, static_cast<const std::uint8_t*>(pixels), width, height, Codec8{srgb});
}

/// Run job(0) .. job(count - 1) on up to `threads` threads (this one among
/// them), each job once; returns each job's exception (null where none).
template <typename Job>
std::vector<std::exception_ptr> forEachParallel(std::size_t count, unsigned threads, const Job& job) {
  std::vector<std::exception_ptr> errors(count);
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < count;) {
      try {
        job(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  const std::size_t extra = std::min<std::size_t>(std::max(threads, 1u), count) - (count > 0);
  std::vector<std::thread> pool;
  pool.reserve(extra);
  try {
    for (std::size_t t = 0; t < extra; ++t) pool.emplace_back(work);
  } catch (const std::system_error&) {
    // no more threads: the ones started and this one do the rest
  }
  work();
  for (std::thread& t : pool) t.join();
  return errors;
}

wt_uint wrapMode(int code) {
  switch (code) {
    case 33071: return WT_WRAP_CLAMP;
    case 33648: return WT_WRAP_MIRROR;
    default: return WT_WRAP_REPEAT;  // 10497, undefined, unknown
  }
}

}  // namespace

// ---------------------------------------------------------------------------
// formats

ImageFileFormat sniffImageFormat(const unsigned char* bytes, std::size_t size) {
  if (!bytes) return ImageFileFormat::Unknown;
  if (startsWith(bytes, size, 0, "\x89PNG\r\n\x1a\n")) return ImageFileFormat::Png;
  if (startsWith(bytes, size, 0, "\xff\xd8\xff")) return ImageFileFormat::Jpeg;
  if (startsWith(bytes, size, 0, "RIFF") && startsWith(bytes, size, 8, "WEBP")) return ImageFileFormat::WebP;
  if (startsWith(bytes, size, 0, "\xabKTX 20\xbb\r\n\x1a\n")) return ImageFileFormat::Ktx2;
  return ImageFileFormat::Unknown;
}

const char* imageFormatName(ImageFileFormat format) {
  switch (format) {
    case ImageFileFormat::Png: return "PNG";
    case ImageFileFormat::Jpeg: return "JPEG";
    case ImageFileFormat::WebP: return "WebP";
    case ImageFileFormat::Ktx2: return "KTX2";
    case ImageFileFormat::Unknown: break;
  }
  return "unknown format";
}

bool isDecodableFormat(ImageFileFormat format) { return format == ImageFileFormat::Png || format == ImageFileFormat::Jpeg; }

bool isDecodableMimeType(std::string_view mimeType) { return mimeType == "image/png" || mimeType == "image/jpeg"; }

double srgbToLinear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

double linearToSrgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// ---------------------------------------------------------------------------
// decoding

namespace {

/// Pixels as stb_image decoded them: RGBA, 8 or 16 bits, in stb's buffer.
struct StbPixels {
  std::uint32_t width = 0, height = 0;
  bool sixteenBit = false;
  std::unique_ptr<void, void (*)(void*)> data{nullptr, stbi_image_free};
};

/// An image file's header as decodeImage checks it.
struct ImageHeader {
  ImageFileFormat format = ImageFileFormat::Unknown;
  std::uint32_t width = 0, height = 0;
  bool sixteenBit = false;
};

/// decodeImage's checks before decoding: the format, the JPEG's Huffman
/// tables and the size (from the header alone, nothing allocated).
ImageHeader readHeader(const unsigned char* bytes, std::size_t size, const std::string& name) {
  if (size == 0) fail(name, "no image data (0 bytes)");
  if (!bytes) fail(name, "no image data (a null pointer)");
  const ImageFileFormat format = sniffImageFormat(bytes, size);
  if (format == ImageFileFormat::Unknown)
    fail(name, "not a PNG or JPEG file (starts with " + firstBytes(bytes, size) + ")");
  if (!isDecodableFormat(format))
    fail(name, std::string(imageFormatName(format)) + " images are not supported (only PNG and JPEG)");
  if (size > std::size_t(INT_MAX)) fail(name, "file too large (" + std::to_string(size) + " bytes)");

  if (format == ImageFileFormat::Jpeg) checkJpegHuffmanTables(name, bytes, size);
  // the header alone first: refuse huge images before allocating them (stb
  // refuses a PNG over 2^30 bytes of pixels itself, saying only "too large")
  if (format == ImageFileFormat::Png && size >= 24 && startsWith(bytes, size, 12, "IHDR")) {
    auto be32 = [&](std::size_t at) {
      return std::uint64_t(bytes[at]) << 24 | std::uint64_t(bytes[at + 1]) << 16 | std::uint64_t(bytes[at + 2]) << 8 |
             bytes[at + 3];
    };
    checkImageSize(name, be32(16), be32(20));
  }
  const int length = int(size);
  int width = 0, height = 0, channels = 0;
  if (!stbi_info_from_memory(bytes, length, &width, &height, &channels))
    fail(name, std::string("cannot read the ") + imageFormatName(format) + " header: " + stbReason());
  checkImageSize(name, std::uint64_t(std::max(width, 0)), std::uint64_t(std::max(height, 0)));
  ImageHeader header;
  header.format = format;
  header.width = std::uint32_t(width), header.height = std::uint32_t(height);
  header.sixteenBit = format == ImageFileFormat::Png && stbi_is_16_bit_from_memory(bytes, length);
  return header;
}

/// decodeImage's decoding, after readHeader gave `header`, without copying
/// the pixels out of stb's buffer. stb_image keeps its failure reason per
/// thread (STBI_THREAD_LOCAL), so decodes may run in parallel.
StbPixels decodePixels(const unsigned char* bytes, std::size_t size, const std::string& name, const ImageHeader& header) {
  const int length = int(size);
  int w = 0, h = 0, channels = 0;
  StbPixels image;
  image.sixteenBit = header.sixteenBit;
  image.data.reset(image.sixteenBit ? static_cast<void*>(stbi_load_16_from_memory(bytes, length, &w, &h, &channels, 4))
                                    : static_cast<void*>(stbi_load_from_memory(bytes, length, &w, &h, &channels, 4)));
  if (!image.data)
    fail(name, std::string("cannot decode the ") + imageFormatName(header.format) + " data: " + stbReason());
  if (std::uint32_t(w) != header.width || std::uint32_t(h) != header.height)
    fail(name, "decoded size " + std::to_string(w) + " x " + std::to_string(h) + " differs from the header's " +
                   std::to_string(header.width) + " x " + std::to_string(header.height));
  image.width = header.width, image.height = header.height;
  return image;
}

}  // namespace

DecodedImage decodeImage(const unsigned char* bytes, std::size_t size, const std::string& name) {
  const StbPixels pixels = decodePixels(bytes, size, name, readHeader(bytes, size, name));
  DecodedImage image;
  image.name = name;
  image.sixteenBit = pixels.sixteenBit;
  image.width = pixels.width, image.height = pixels.height;
  const std::size_t values = std::size_t(image.width) * image.height * 4;  // <= 2^30: checkImageSize
  if (image.sixteenBit) {
    const auto* p = static_cast<const std::uint16_t*>(pixels.data.get());
    image.rgba16.assign(p, p + values);
  } else {
    const auto* p = static_cast<const std::uint8_t*>(pixels.data.get());
    image.rgba8.assign(p, p + values);
  }
  return image;
}

// ---------------------------------------------------------------------------
// packing

std::uint32_t TextureSet::addImage(const DecodedImage& image, bool srgb) {
  const std::string name = image.name.empty() ? "image " + std::to_string(m_images.size()) : image.name;
  checkImageSize(name, image.width, image.height);
  const std::size_t values = std::size_t(image.width) * image.height * 4;
  if ((image.sixteenBit ? image.rgba16.size() : image.rgba8.size()) != values)
    fail(name, "has " + std::to_string(image.sixteenBit ? image.rgba16.size() : image.rgba8.size()) +
                   " channel values, not width x height x 4 = " + std::to_string(values));
  const std::uint64_t words = pyramidWords(image.width, image.height, image.sixteenBit);
  // every level's texels must stay addressable with a 32-bit offset
  if (texels.size() + words > (std::uint64_t(1) << 32))
    fail(name, "the scene's textures pass 2^32 texel words (16 GiB) with this image");

  Image entry{wt_uint(levels.size()), 0, (srgb ? WT_TEXTURE_SRGB : 0u) | (image.sixteenBit ? WT_TEXTURE_16BIT : 0u)};
  const std::size_t base = texels.size();
  texels.resize(base + words);
  const void* pixels = image.sixteenBit ? static_cast<const void*>(image.rgba16.data()) : image.rgba8.data();
  writePyramid(texels.data() + base, wt_uint(base), levels, pixels, image.width, image.height, image.sixteenBit, srgb);
  entry.levelCount = wt_uint(levels.size()) - entry.firstLevel;
  m_images.push_back(entry);
  return std::uint32_t(m_images.size() - 1);
}

std::vector<std::uint32_t> TextureSet::addEncodedImages(const std::vector<EncodedImage>& images, unsigned threads) {
  if (threads == 0) threads = std::max(std::thread::hardware_concurrency(), 1u);
  // the headers first (cheap): their sizes place every image, so the texel
  // array is sized, and its pages first touched, while the images decode
  std::vector<ImageHeader> headers(images.size());
  std::vector<std::exception_ptr> errors(images.size());
  std::vector<std::uint64_t> offsets(images.size());
  std::uint64_t end = texels.size();
  for (std::size_t i = 0; i < images.size(); ++i) {
    try {
      headers[i] = readHeader(images[i].bytes, images[i].size, images[i].name);
    } catch (const TextureError&) {
      errors[i] = std::current_exception();
      continue;
    }
    offsets[i] = end;
    end += pyramidWords(headers[i].width, headers[i].height, headers[i].sixteenBit);
  }
  // past 2^32 words an error follows (below, for the image that passes it): no array that large
  const bool presize = end <= (std::uint64_t(1) << 32);
  const std::size_t originalSize = texels.size();
  // job 0 sizes the array; job i + 1 decodes image i and, once the array is
  // sized, writes its pyramid there (no pass waits for all images of the last)
  std::vector<std::vector<WtTextureLevel>> imageLevels(images.size());
  std::promise<void> sizedPromise;
  std::shared_future<void> sized = sizedPromise.get_future().share();
  const std::vector<std::exception_ptr> jobErrors = forEachParallel(images.size() + 1, threads, [&](std::size_t job) {
    if (job == 0) {
      try {
        if (presize) texels.resize(end);
        sizedPromise.set_value();
      } catch (...) {
        sizedPromise.set_exception(std::current_exception());
        throw;
      }
      return;
    }
    const std::size_t i = job - 1;
    if (errors[i]) return;
    const StbPixels pixels = decodePixels(images[i].bytes, images[i].size, images[i].name, headers[i]);
    sized.get();  // job 0 was taken first, so it is running or done: no deadlock
    if (!presize) return;  // an image passes 2^32 words: an error follows
    writePyramid(texels.data() + offsets[i], wt_uint(offsets[i]), imageLevels[i], pixels.data.get(), pixels.width,
                 pixels.height, pixels.sixteenBit, images[i].srgb);
  });
  auto restore = [&] { texels.resize(originalSize); };
  if (jobErrors[0]) std::rethrow_exception(jobErrors[0]);  // out of memory: the set is as it was
  for (std::size_t i = 0; i < images.size(); ++i) {
    // the first failure in order, as one image after another would meet it
    if (!errors[i]) errors[i] = jobErrors[i + 1];
    if (errors[i]) {
      restore();
      std::rethrow_exception(errors[i]);
    }
    if (offsets[i] + pyramidWords(headers[i].width, headers[i].height, headers[i].sixteenBit) > (std::uint64_t(1) << 32)) {
      restore();
      fail(images[i].name, "the scene's textures pass 2^32 texel words (16 GiB) with this image");
    }
  }
  std::vector<std::uint32_t> indices;
  indices.reserve(images.size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    const wt_uint flags = (images[i].srgb ? WT_TEXTURE_SRGB : 0u) | (headers[i].sixteenBit ? WT_TEXTURE_16BIT : 0u);
    m_images.push_back({wt_uint(levels.size()), wt_uint(imageLevels[i].size()), flags});
    levels.insert(levels.end(), imageLevels[i].begin(), imageLevels[i].end());
    indices.push_back(std::uint32_t(m_images.size() - 1));
  }
  return indices;
}

std::uint32_t TextureSet::addTexture(std::uint32_t imageIndex, int wrapS, int wrapT, int magFilter, int minFilter) {
  if (imageIndex >= m_images.size())
    throw TextureError("texture: image " + std::to_string(imageIndex) + " was not added (" +
                       std::to_string(m_images.size()) + " images)");
  const Image& image = m_images[imageIndex];
  wt_uint flags = image.flags | wrapMode(wrapS) << WT_TEXTURE_WRAP_S_SHIFT | wrapMode(wrapT) << WT_TEXTURE_WRAP_T_SHIFT;
  if (magFilter != 9728) flags |= WT_TEXTURE_MAG_LINEAR;  // LINEAR, undefined, unknown
  wt_uint minLinear = 1, mip = WT_MIP_LINEAR;             // LINEAR_MIPMAP_LINEAR, undefined, unknown
  switch (minFilter) {
    case 9728: minLinear = 0, mip = WT_MIP_NONE; break;     // NEAREST
    case 9729: minLinear = 1, mip = WT_MIP_NONE; break;     // LINEAR
    case 9984: minLinear = 0, mip = WT_MIP_NEAREST; break;  // NEAREST_MIPMAP_NEAREST
    case 9985: minLinear = 1, mip = WT_MIP_NEAREST; break;  // LINEAR_MIPMAP_NEAREST
    case 9986: minLinear = 0, mip = WT_MIP_LINEAR; break;   // NEAREST_MIPMAP_LINEAR
    default: break;
  }
  if (minLinear) flags |= WT_TEXTURE_MIN_LINEAR;
  flags |= mip << WT_TEXTURE_MIP_SHIFT;
  textures.push_back({image.firstLevel, image.levelCount, flags, 0});
  return std::uint32_t(textures.size() - 1);
}

std::uint32_t TextureSet::append(const TextureSet& other) {
  if (texels.size() + other.texels.size() > std::numeric_limits<wt_uint>::max())
    throw TextureError("textures: more than 2^32 texel words in one scene");
  const auto texelBase = wt_uint(texels.size()), levelBase = wt_uint(levels.size());
  const auto textureBase = std::uint32_t(textures.size());
  texels.insert(texels.end(), other.texels.begin(), other.texels.end());
  for (WtTextureLevel l : other.levels) {
    l.offset += texelBase;
    levels.push_back(l);
  }
  for (WtTexture t : other.textures) {
    t.first_level += levelBase;
    textures.push_back(t);
  }
  for (Image image : other.m_images) {
    image.firstLevel += levelBase;
    m_images.push_back(image);
  }
  return textureBase;
}

std::uint32_t TextureSet::append(TextureSet&& other) {
  if (!texels.empty()) {
    const std::uint32_t base = append(other);
    other = TextureSet{};
    return base;
  }
  // offsets stay: other's texels start at word 0 here too
  std::vector<wt_uint> moved = std::move(other.texels);
  other.texels.clear();
  const std::uint32_t base = append(other);
  texels = std::move(moved);
  other = TextureSet{};
  return base;
}

std::size_t TextureSet::bytes() const {
  return texels.size() * sizeof(wt_uint) + levels.size() * sizeof(WtTextureLevel) +
         textures.size() * sizeof(WtTexture);
}

}  // namespace wt
