// The library's version (CEodeGetVersion, CEodeGetVersionNumber, docs/api.md "Utilities"): the
// project version of CMakeLists.txt, the same in the configured header and in the library, and
// a buffer that cannot hold it refused without being written.
#include <ceode/ceode.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace {

// "X.Y.Z" of `project(CEODE VERSION X.Y.Z ...)` in the source tree's CMakeLists.txt.
std::string ProjectVersion() {
  std::ifstream in(std::string(CEODE_SOURCE_DIR) + "/CMakeLists.txt");
  std::stringstream text;
  text << in.rdbuf();
  std::smatch m;
  const std::string s = text.str();
  if (!std::regex_search(s, m, std::regex(R"(project\(CEODE VERSION ([0-9]+\.[0-9]+\.[0-9]+))"))) {
    return "";
  }
  return m[1];
}

TEST(Version, IsTheProjectVersionInTheHeaderAndInTheLibrary) {
  const std::string project = ProjectVersion();
  ASSERT_FALSE(project.empty()) << "no project(CEODE VERSION ...) in CMakeLists.txt";
  char version[32];
  ASSERT_EQ(CEodeGetVersion(version, sizeof version), CE_SUCCESS);
  std::string expected = project;
  if (std::strlen(CEODE_VERSION_LABEL) > 0) expected += std::string("-") + CEODE_VERSION_LABEL;
  EXPECT_EQ(std::string(version), expected);
  EXPECT_EQ(std::string(CEODE_VERSION), expected);

  int major = -1, minor = -1, patch = -1;
  char label[32] = "unset";
  ASSERT_EQ(CEodeGetVersionNumber(&major, &minor, &patch, label, sizeof label), CE_SUCCESS);
  EXPECT_EQ(std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch),
            project);
  EXPECT_EQ(major, CEODE_VERSION_MAJOR);
  EXPECT_EQ(minor, CEODE_VERSION_MINOR);
  EXPECT_EQ(patch, CEODE_VERSION_PATCH);
  EXPECT_STREQ(label, CEODE_VERSION_LABEL);
}

TEST(Version, RefusesABufferThatCannotHoldItAndLeavesTheBufferAlone) {
  const int needed = static_cast<int>(std::strlen(CEODE_VERSION)) + 1;
  char version[32];
  std::memset(version, 'x', sizeof version);
  EXPECT_EQ(CEodeGetVersion(version, needed - 1), CE_ILL_INPUT);  // no room for the '\0'
  EXPECT_EQ(version[0], 'x');
  EXPECT_EQ(CEodeGetVersion(version, 0), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetVersion(nullptr, 32), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetVersion(version, needed), CE_SUCCESS);  // exactly enough
  EXPECT_STREQ(version, CEODE_VERSION);

  int major = -1, minor = -1, patch = -1;
  char label[32];
  EXPECT_EQ(CEodeGetVersionNumber(nullptr, &minor, &patch, label, sizeof label), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetVersionNumber(&major, nullptr, &patch, label, sizeof label), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetVersionNumber(&major, &minor, nullptr, label, sizeof label), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetVersionNumber(&major, &minor, &patch, nullptr, sizeof label), CE_ILL_INPUT);
  const int label_needed = static_cast<int>(std::strlen(CEODE_VERSION_LABEL)) + 1;
  EXPECT_EQ(CEodeGetVersionNumber(&major, &minor, &patch, label, label_needed - 1), CE_ILL_INPUT);
  EXPECT_EQ(major, -1);  // nothing written on a refusal
}

}  // namespace
