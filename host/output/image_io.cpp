#include "output/image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <random>
#include <system_error>

namespace wt {
namespace {

std::filesystem::path temporaryPath(const std::filesystem::path& path) {
  std::random_device rd;
  // Hidden, beside the target (same file system, so rename is atomic).
  std::string name = ".";
  name += path.filename().string();
  name += ".tmp";
  name += std::to_string(rd() % 1000000);
  return path.parent_path() / name;
}

/// Write with `writer` to a temporary file beside `path`, then rename.
template <typename Writer>
void writeAtomically(const std::filesystem::path& path, Writer writer) {
  std::filesystem::path tmp = temporaryPath(path);
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
}

void writeExr(const std::filesystem::path& path, const Image& image) {
  // Beside RGB, the variance of each pixel's mean (sample variance / samples)
  // as a layer, so the image can serve as a reference with known noise.
  const std::size_t pixels = std::size_t(image.width) * std::size_t(std::max(image.height, 0));
  std::vector<float> meanVariance;
  if (image.rgbVariance.size() == 3 * pixels && image.samples.size() == pixels) {
    meanVariance.resize(3 * pixels);
    for (std::size_t p = 0; p < pixels; ++p)
      for (int c = 0; c < 3; ++c)
        meanVariance[3 * p + c] = image.samples[p] > 0 ? image.rgbVariance[3 * p + c] / float(image.samples[p]) : 0.0f;
  }
  try {
    Imf::Header header(image.width, image.height);
    for (const char* name : {"R", "G", "B"}) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    if (!meanVariance.empty())
      for (const char* name : {"mean_variance.R", "mean_variance.G", "mean_variance.B"})
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer fb;
    const std::size_t xStride = 3 * sizeof(float), yStride = xStride * image.width;
    char* base = reinterpret_cast<char*>(const_cast<float*>(image.rgb.data()));
    fb.insert("R", Imf::Slice(Imf::FLOAT, base + 0, xStride, yStride));
    fb.insert("G", Imf::Slice(Imf::FLOAT, base + 4, xStride, yStride));
    fb.insert("B", Imf::Slice(Imf::FLOAT, base + 8, xStride, yStride));
    if (!meanVariance.empty()) {
      char* var = reinterpret_cast<char*>(meanVariance.data());
      fb.insert("mean_variance.R", Imf::Slice(Imf::FLOAT, var + 0, xStride, yStride));
      fb.insert("mean_variance.G", Imf::Slice(Imf::FLOAT, var + 4, xStride, yStride));
      fb.insert("mean_variance.B", Imf::Slice(Imf::FLOAT, var + 8, xStride, yStride));
    }
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    throw OutputError(path.string() + ": writing EXR failed: " + e.what());
  }
}

void writePng(const std::filesystem::path& path, const Image& image) {
  if (!stbi_write_png(path.c_str(), image.width, image.height, 4, image.srgba.data(),
                      image.width * 4))
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
  std::filesystem::path probe = temporaryPath(path);
  {
    std::ofstream out(probe);
    if (!out) throw OutputError(path.string() + ": folder '" + dir.string() + "' is not writable");
  }
  std::filesystem::remove(probe, ec);
}

void writeImage(const std::filesystem::path& path, const Image& image) {
  ImageFormat format = imageFormatFor(path);
  writeAtomically(path, [&](const std::filesystem::path& tmp) {
    if (format == ImageFormat::Exr)
      writeExr(tmp, image);
    else
      writePng(tmp, image);
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
    return image;
  } catch (const std::exception& e) {
    throw OutputError(path.string() + ": reading EXR failed: " + e.what());
  }
}

}  // namespace wt
