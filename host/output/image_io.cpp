#include "output/image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIntAttribute.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <fstream>
#include <random>
#include <system_error>
#include <thread>
#include <unistd.h>

namespace wt {
namespace {

/// Write with `writer` to a temporary file beside `path`, then rename.
template <typename Writer>
void writeAtomically(const std::filesystem::path& path, Writer writer) {
  std::filesystem::path tmp = temporaryPathFor(path);
  try {
    writer(tmp);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw OutputError(path.string() + ": cannot replace the file: " + ec.message());
  }
  removeStaleTemporaries(path);
}

/// One channel of an EXR: `base` points at pixel 0's value, `stride` bytes apart.
struct ExrChannel {
  std::string name;
  Imf::PixelType type;
  const void* base;
  std::size_t stride;
};

void writeExrChannels(const std::filesystem::path& path, int width, int height, const std::vector<ExrChannel>& channels,
                      int samplesDone = 0) {
  try {
    Imf::Header header(width, height);
    // what the image holds, readable where it outlived its render (a killed job's periodic image)
    if (samplesDone > 0) header.insert(kExrSamplesAttribute, Imf::IntAttribute(samplesDone));
    for (const ExrChannel& c : channels) header.channels().insert(c.name, Imf::Channel(c.type));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer fb;
    for (const ExrChannel& c : channels)
      fb.insert(c.name, Imf::Slice(c.type, static_cast<char*>(const_cast<void*>(c.base)), c.stride,
                                   c.stride * std::size_t(width)));
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::exception& e) {
    throw OutputError(path.string() + ": writing EXR failed: " + e.what());
  }
}

/// Channels named prefix + names[k] of `components`-float pixels.
void addFloatChannels(std::vector<ExrChannel>& out, const std::string& prefix, const std::vector<float>& data,
                      std::initializer_list<const char*> names) {
  std::size_t k = 0;
  for (const char* n : names) out.push_back({prefix + n, Imf::FLOAT, data.data() + k++, names.size() * sizeof(float)});
}

/// The variance of each pixel's mean (sample variance / samples); empty without the variance.
std::vector<float> meanVarianceOf(const Image& image) {
  const std::size_t pixels = std::size_t(image.width) * std::size_t(std::max(image.height, 0));
  std::vector<float> meanVariance;
  if (image.rgbVariance.size() == 3 * pixels && image.samples.size() == pixels) {
    meanVariance.resize(3 * pixels);
    for (std::size_t p = 0; p < pixels; ++p)
      for (int c = 0; c < 3; ++c)
        meanVariance[3 * p + c] = image.samples[p] > 0 ? image.rgbVariance[3 * p + c] / float(image.samples[p]) : 0.0f;
  }
  return meanVariance;
}

/// The channels of `aov` named prefix + channel; meanVariance the image's (meanVarianceOf).
void addAovChannels(std::vector<ExrChannel>& out, const std::filesystem::path& path, const Image& image, Aov aov,
                    const std::string& prefix, const std::vector<float>& meanVariance) {
  const Aovs& a = image.aovs;
  if (aov == Aov::Variance) {
    if (meanVariance.empty())
      throw OutputError(path.string() + ": the image has no variance for the AOV 'variance'");
    addFloatChannels(out, prefix, meanVariance, {"R", "G", "B"});
    return;
  }
  if (a.empty())
    throw OutputError(path.string() + ": the render recorded no AOVs, so '" + std::string(aovName(aov)) +
                      "' cannot be written");
  switch (aov) {
    case Aov::Albedo: addFloatChannels(out, prefix, a.albedo, {"R", "G", "B"}); break;
    case Aov::Normal:
    case Aov::Position: {
      // a separate image is RGB, so that any viewer and OIDN's tools read it
      const bool layer = !prefix.empty();
      addFloatChannels(out, prefix, aov == Aov::Normal ? a.normal : a.position,
                       layer ? std::initializer_list<const char*>{"X", "Y", "Z"}
                             : std::initializer_list<const char*>{"R", "G", "B"});
      break;
    }
    case Aov::Depth: addFloatChannels(out, prefix, a.depth, {"Z"}); break;
    case Aov::Material: out.push_back({prefix + "id", Imf::UINT, a.material.data(), sizeof(std::uint32_t)}); break;
    case Aov::Instance:
      out.push_back({prefix + "id", Imf::UINT, a.instance.data(), sizeof(std::uint32_t)});
      out.push_back({prefix + "primitive", Imf::UINT, a.primitive.data(), sizeof(std::uint32_t)});
      break;
    case Aov::Variance: break;
  }
}

void writeExr(const std::filesystem::path& path, const Image& image, std::span<const Aov> aovs) {
  // Beside RGB, the variance of each pixel's mean as a layer, so the image
  // can serve as a reference with known noise; then the AOVs asked for.
  const std::vector<float> meanVariance = meanVarianceOf(image);
  std::vector<ExrChannel> channels;
  addFloatChannels(channels, "", image.rgb, {"R", "G", "B"});
  if (!meanVariance.empty()) addFloatChannels(channels, "mean_variance.", meanVariance, {"R", "G", "B"});
  for (Aov aov : aovs)
    if (aov != Aov::Variance)  // the mean_variance layer above
      addAovChannels(channels, path, image, aov, std::string(aovName(aov)) + ".", meanVariance);
  writeExrChannels(path, image.width, image.height, channels, image.samplesDone);
}

/// A PNG chunk: length, type, data, CRC over type and data.
void appendPngChunk(std::string& out, const char (&type)[5], const std::string& data) {
  auto be32 = [&out](std::uint32_t v) {
    const char bytes[4] = {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
    out.append(bytes, 4);
  };
  be32(std::uint32_t(data.size()));
  const std::size_t crcFrom = out.size();
  out.append(type, 4);
  out += data;
  be32(std::uint32_t(crc32(0, reinterpret_cast<const Bytef*>(out.data() + crcFrom), uInt(out.size() - crcFrom))));
}

/// Rows [first, last) of `image`, each filtered by its difference to the
/// one above (PNG filter 2), as raw deflate data: the final block where
/// `final`, else ended by a sync flush so that the next part can follow it.
/// False where zlib fails.
bool deflatePngRows(const Image& image, std::size_t first, std::size_t last, bool final, std::string& out,
                    uLong& adler) {
  const std::size_t rowBytes = std::size_t(image.width) * 4;
  std::string raw((last - first) * (rowBytes + 1), '\0');
  for (std::size_t y = first; y < last; ++y) {
    char* row = raw.data() + (y - first) * (rowBytes + 1);
    const std::uint8_t* src = image.srgba.data() + y * rowBytes;
    row[0] = 2;
    for (std::size_t x = 0; x < rowBytes; ++x) row[1 + x] = char(y == 0 ? src[x] : std::uint8_t(src[x] - src[x - rowBytes]));
  }
  adler = adler32(adler32(0, nullptr, 0), reinterpret_cast<const Bytef*>(raw.data()), uInt(raw.size()));
  z_stream z{};
  // the fastest level, runs only (Z_RLE): the filtered rows of renders, noisy or converged,
  // compress smaller and faster that way than with zlib's default matching
  if (deflateInit2(&z, 1, Z_DEFLATED, -15, 8, Z_RLE) != Z_OK) return false;
  out.resize(deflateBound(&z, uLong(raw.size())) + 16);
  z.next_in = reinterpret_cast<Bytef*>(raw.data());
  z.avail_in = uInt(raw.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = uInt(out.size());
  const int result = deflate(&z, final ? Z_FINISH : Z_SYNC_FLUSH);
  const bool done = final ? result == Z_STREAM_END : result == Z_OK && z.avail_in == 0;
  out.resize(out.size() - z.avail_out);
  deflateEnd(&z);
  return done;
}

void writePng(const std::filesystem::path& path, const Image& image) {
  // Deflated in two halves at once where there are enough rows (one zlib
  // stream: the first half ends on a sync flush, the checksums combine): the
  // write is the last serial step of a render. The same bytes on any machine.
  const std::size_t height = std::size_t(image.height), rowBytes = std::size_t(image.width) * 4;
  const bool split = height >= 2 && height * rowBytes >= (std::size_t(1) << 18);
  const std::size_t middle = split ? height / 2 : height;
  std::string second;
  uLong secondAdler = 1;
  bool secondDone = true;
  const auto deflateSecond = [&]() { secondDone = deflatePngRows(image, middle, height, true, second, secondAdler); };
  std::thread helper;
  if (split) {
    try {
      helper = std::thread(deflateSecond);
    } catch (const std::system_error&) {
      deflateSecond();  // no thread to be had: the same bytes, one half after the other
    }
  }
  std::string body;
  uLong adler = 1;
  const bool firstDone = deflatePngRows(image, 0, middle, !split, body, adler);
  if (helper.joinable()) helper.join();
  if (!firstDone || !secondDone) throw OutputError(path.string() + ": compressing the PNG failed");
  if (split) adler = adler32_combine(adler, secondAdler, z_off_t((height - middle) * (rowBytes + 1)));
  // zlib header (deflate, 32 KB window, fastest level) and the Adler-32 of all rows
  std::string packed("\x78\x01", 2);
  packed += body;
  packed += second;
  for (int shift = 24; shift >= 0; shift -= 8) packed += char((adler >> shift) & 0xff);

  std::string header(13, '\0');  // IHDR: width, height, 8 bits, RGBA, deflate, adaptive filters, not interlaced
  for (int i = 0; i < 4; ++i) {
    header[std::size_t(i)] = char(std::uint32_t(image.width) >> (24 - 8 * i));
    header[std::size_t(4 + i)] = char(std::uint32_t(image.height) >> (24 - 8 * i));
  }
  header[8] = 8;
  header[9] = 6;
  std::string file("\x89PNG\r\n\x1a\n", 8);
  appendPngChunk(file, "IHDR", header);
  appendPngChunk(file, "IDAT", packed);
  appendPngChunk(file, "IEND", std::string());
  std::ofstream out(path, std::ios::binary);
  if (!out.write(file.data(), std::streamsize(file.size())) || !out.flush())
    throw OutputError(path.string() + ": writing PNG failed");
}

}  // namespace

ImageFormat imageFormatFor(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".exr") return ImageFormat::Exr;
  if (ext == ".png") return ImageFormat::Png;
  throw OutputError(path.string() + ": unknown image format '" + ext + "' (use .exr or .png)");
}

void checkWritable(const std::filesystem::path& path) {
  imageFormatFor(path);
  std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw OutputError(path.string() + ": folder '" + dir.string() + "' does not exist");
  if (std::filesystem::is_directory(path, ec))
    throw OutputError(path.string() + ": is a folder");
  std::filesystem::path probe = temporaryPathFor(path);
  {
    std::ofstream out(probe);
    if (!out) throw OutputError(path.string() + ": folder '" + dir.string() + "' is not writable");
  }
  std::filesystem::remove(probe, ec);
}

std::string_view aovName(Aov aov) {
  switch (aov) {
    case Aov::Albedo: return "albedo";
    case Aov::Normal: return "normal";
    case Aov::Depth: return "depth";
    case Aov::Position: return "position";
    case Aov::Material: return "material";
    case Aov::Instance: return "instance";
    case Aov::Variance: return "variance";
  }
  return "?";
}

std::vector<Aov> parseAovList(std::string_view list) {
  std::vector<bool> asked(std::size(kAllAovs), false);
  std::size_t start = 0;
  while (start <= list.size()) {
    std::size_t end = std::min(list.find(',', start), list.size());
    std::string_view name = list.substr(start, end - start);
    if (name == "all") {
      asked.assign(asked.size(), true);
    } else {
      std::size_t k = 0;
      while (k < std::size(kAllAovs) && aovName(kAllAovs[k]) != name) ++k;
      if (k == std::size(kAllAovs)) {
        std::string known;
        for (Aov a : kAllAovs) known += std::string(aovName(a)) + ", ";
        throw std::invalid_argument(name.empty() ? "--aov: an empty name in '" + std::string(list) + "'"
                                                 : "--aov: unknown AOV '" + std::string(name) + "' (known: " +
                                                       known + "all)");
      }
      asked[k] = true;
    }
    start = end + 1;
  }
  std::vector<Aov> out;
  for (std::size_t k = 0; k < asked.size(); ++k)
    if (asked[k]) out.push_back(kAllAovs[k]);
  return out;
}

void writeImage(const std::filesystem::path& path, const Image& image, std::span<const Aov> aovs) {
  ImageFormat format = imageFormatFor(path);
  for (Aov aov : aovs)
    if (aov != Aov::Variance && image.aovs.empty())
      throw OutputError(path.string() + ": the render recorded no AOVs, so '" + std::string(aovName(aov)) +
                        "' cannot be written");
  if (format == ImageFormat::Png &&
      (image.width <= 0 || image.height <= 0 ||
       image.srgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4))
    throw OutputError(path.string() + ": no 8-bit pixels to write (" + std::to_string(image.width) + " x " +
                      std::to_string(image.height) + " image, " + std::to_string(image.srgba.size()) + " bytes)");
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    if (format == ImageFormat::Exr)
      writeExr(tmp, image, aovs);
    else
      writePng(tmp, image);
  });
}

void writeAovImage(const std::filesystem::path& path, const Image& image, Aov aov) {
  if (imageFormatFor(path) != ImageFormat::Exr) throw OutputError(path.string() + ": an AOV image is written as .exr");
  std::vector<float> meanVariance = meanVarianceOf(image);
  std::vector<ExrChannel> channels;
  addAovChannels(channels, path, image, aov, "", meanVariance);
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    writeExrChannels(tmp, image.width, image.height, channels);
  });
}

Image readExr(const std::filesystem::path& path) {
  try {
    Imf::InputFile file(path.c_str());
    Imath::Box2i dw = file.header().dataWindow();
    Image image;
    image.width = dw.max.x - dw.min.x + 1;
    image.height = dw.max.y - dw.min.y + 1;
    image.rgb.assign(3 * std::size_t(image.width) * image.height, 0.0f);
    Imf::FrameBuffer fb;
    const std::size_t xStride = 3 * sizeof(float), yStride = xStride * image.width;
    char* base = reinterpret_cast<char*>(image.rgb.data()) -
                 (dw.min.x * xStride + dw.min.y * yStride);
    fb.insert("R", Imf::Slice(Imf::FLOAT, base + 0, xStride, yStride));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + 4, xStride, yStride));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 8, xStride, yStride));
    // a variance layer written by wavetrace comes back as 1 sample of that variance
    bool hasVariance = file.header().channels().findChannel("mean_variance.R") != nullptr;
    if (hasVariance) {
      image.rgbVariance.assign(image.rgb.size(), 0.0f);
      image.samples.assign(std::size_t(image.width) * image.height, 1u);
      char* var = reinterpret_cast<char*>(image.rgbVariance.data()) - (dw.min.x * xStride + dw.min.y * yStride);
      fb.insert("mean_variance.R", Imf::Slice(Imf::FLOAT, var + 0, xStride, yStride));
      fb.insert("mean_variance.G", Imf::Slice(Imf::FLOAT, var + 4, xStride, yStride));
      fb.insert("mean_variance.B", Imf::Slice(Imf::FLOAT, var + 8, xStride, yStride));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    if (const auto* n = file.header().findTypedAttribute<Imf::IntAttribute>(kExrSamplesAttribute))
      image.samplesDone = n->value();
    return image;
  } catch (const std::exception& e) {
    throw OutputError(path.string() + ": reading EXR failed: " + e.what());
  }
}

namespace {
// Built by appending: gcc 12 warns falsely (-Wrestrict) on "." + string.
std::string temporaryPrefix(const std::filesystem::path& path) {
  std::string prefix = ".";
  prefix += path.filename().string();
  prefix += ".tmp";
  return prefix;
}
}  // namespace

std::filesystem::path temporaryPathFor(const std::filesystem::path& path) {
  std::random_device rd;
  std::string name = temporaryPrefix(path);
  name += std::to_string(::getpid());
  name += '.';
  name += std::to_string(rd() % 1000000);
  return path.parent_path() / name;
}

void removeStaleTemporaries(const std::filesystem::path& path) {
  const std::string prefix = temporaryPrefix(path);
  std::error_code ec;
  const std::filesystem::path folder = path.parent_path().empty() ? "." : path.parent_path();
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::size_t dot = name.find('.', prefix.size());
    const std::string digits = name.substr(prefix.size(), dot - prefix.size());
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const pid_t pid = pid_t(std::stol(digits));
    // Another process on this machine may be writing it right now: only a dead writer's file goes.
    if (pid != ::getpid() && ::kill(pid, 0) != 0 && errno == ESRCH) std::filesystem::remove(entry.path(), ec);
  }
}

}  // namespace wt
