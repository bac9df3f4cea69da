// Precompiled for every test target: the headers nearly every test file
// parses (gtest, OpenCL's C++ bindings, glm, the standard library), so each
// file's compile starts past them.
#include <gtest/gtest.h>
#include <CL/opencl.hpp>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>
