// The implementations of the header-only parsers the loaders use, compiled
// into the fuzz build so that coverage and the sanitizers see inside them.
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_INCLUDE_STB_IMAGE  // included above, with its implementation
#include <tiny_gltf.h>
