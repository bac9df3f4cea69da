// Textures on the host: PNG and JPEG decoded with stb_image, a mip pyramid
// per image, and the packing the kernels read (kernels/shared/textures.h,
// sampled by kernels/materials/texture.cl).
#pragma once

#include "shared/textures.h"
#include "shared/types.h"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace wt {

/// An image that cannot be decoded or packed. what() starts with the image's
/// name, e.g. "textures/wood.png: cannot decode: bad zlib header".
struct TextureError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Largest image decodeImage accepts: per side, and in texels (a 16-bit one
/// of that many texels with its mips is 2.7 GiB of texels).
constexpr std::uint32_t kMaxTextureSide = 32768;
constexpr std::uint64_t kMaxTextureTexels = std::uint64_t(1) << 28;

/// Image file formats told apart by their first bytes.
enum class ImageFileFormat { Png, Jpeg, WebP, Ktx2, Unknown };

/// The format of an image file's bytes (magic numbers only, nothing decoded).
ImageFileFormat sniffImageFormat(const unsigned char* bytes, std::size_t size);
/// "PNG", "JPEG", "WebP", "KTX2" or "unknown format", for messages.
const char* imageFormatName(ImageFileFormat format);
/// Whether decodeImage reads this format: PNG and JPEG. WebP
/// (EXT_texture_webp) and KTX2 (KHR_texture_basisu) are not.
bool isDecodableFormat(ImageFileFormat format);
/// Whether a glTF image's mimeType is one decodeImage reads ("image/png", "image/jpeg").
bool isDecodableMimeType(std::string_view mimeType);

/// Decoded pixels, always RGBA, row-major from the top row (the file's
/// first, glTF's v = 0). Exactly one of rgba8 and rgba16 holds
/// width * height * 4 values, per `sixteenBit`.
struct DecodedImage {
  std::uint32_t width = 0, height = 0;
  bool sixteenBit = false;          ///< 16-bit PNG: rgba16; otherwise rgba8
  std::vector<std::uint8_t> rgba8;
  std::vector<std::uint16_t> rgba16;
  std::string name;                 ///< for messages
};

/// Decode a PNG (8- or 16-bit) or JPEG from memory. Grey becomes RGB with
/// the grey replicated, a missing alpha is opaque. `name` (a file, or the
/// glTF image's name or index) starts every message. Throws TextureError for
/// any other format, undecodable or truncated bytes, and images larger than
/// kMaxTextureSide per side or kMaxTextureTexels.
DecodedImage decodeImage(const unsigned char* bytes, std::size_t size, const std::string& name);

/// An image file's bytes, for TextureSet::addEncodedImages.
struct EncodedImage {
  const unsigned char* bytes = nullptr;  ///< not owned: must outlive the call
  std::size_t size = 0;
  std::string name;  ///< starts every message, as decodeImage's `name`
  bool srgb = false;
};

/// Every texture of a scene packed as the kernels read them
/// (kernels/shared/textures.h).
///
/// Mip levels go down to 1 x 1, each floor(half) of the one above (at least
/// 1). A level's texel is the exact box filter of its footprint on the level
/// above: two taps with weights 1/2 along an even axis; along an odd axis of
/// 2n + 1 texels (n >= 1), texel x of n covers three with weights
/// (n - x, n, x + 1) / (2n + 1); an axis of one texel is copied. sRGB images
/// are filtered in linear light and re-encoded with the exact transfer
/// functions, rounded to nearest; alpha and linear images are filtered as
/// stored. Each level is made from the stored (rounded) level above.
class TextureSet {
 public:
  /// Build `image`'s levels, append its texels and return its image index.
  /// sRGB-ness changes the mips, so the caller adds a glTF image once per
  /// (image, srgb) pair it meets: an image used both as base colour (sRGB)
  /// and as a linear map is added twice. Throws TextureError when the
  /// texel array would pass 2^32 uints.
  std::uint32_t addImage(const DecodedImage& image, bool srgb);

  /// decodeImage and addImage for each of `images` in turn, the decoding
  /// and the mip building spread over up to `threads` threads (0: the
  /// hardware's); the result is the same, bit for bit, on any number.
  /// Returns their image indices, in order. Throws the TextureError of the
  /// first image (in order) that fails, as addImage would, adding none.
  std::vector<std::uint32_t> addEncodedImages(const std::vector<EncodedImage>& images, unsigned threads = 0);

  /// A texture of image `imageIndex` (from addImage) with a glTF sampler:
  /// wrapS, wrapT, magFilter and minFilter are glTF's codes, -1 where the
  /// sampler (or the whole sampler) is undefined; an unknown code is taken
  /// as undefined. Returns the index into `textures`. Throws TextureError
  /// for an image index not returned by addImage.
  std::uint32_t addTexture(std::uint32_t imageIndex, int wrapS = -1, int wrapT = -1, int magFilter = -1,
                           int minFilter = -1);

  std::size_t imageCount() const { return m_images.size(); }
  /// Bytes of the three arrays together, for -v reporting.
  std::size_t bytes() const;
  /// Append every image and texture of `other` (a scene placed in another);
  /// returns the index its texture 0 now has. Throws TextureError when the
  /// texel array would pass 2^32 uints.
  std::uint32_t append(const TextureSet& other);
  /// The same for a set the caller gives up: into a set without texels its
  /// texels move (no copy); otherwise they are copied and `other` is freed.
  std::uint32_t append(TextureSet&& other);

  std::vector<wt_uint> texels;          ///< __global const uint*; empty until an image is added
  std::vector<WtTextureLevel> levels;   ///< __global const WtTextureLevel*
  std::vector<WtTexture> textures;      ///< __global const WtTexture*

 private:
  struct Image {
    wt_uint firstLevel, levelCount, flags;  ///< flags: WT_TEXTURE_SRGB and WT_TEXTURE_16BIT
  };
  std::vector<Image> m_images;
};

/// The exact sRGB transfer functions (IEC 61966-2-1), on [0, 1].
double srgbToLinear(double encoded);
double linearToSrgb(double linear);

}  // namespace wt
