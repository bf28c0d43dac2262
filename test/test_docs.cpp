// The documentation against the library (ctest label "docs"): every named set the library knows
// (CEodeGetNumMethods, CEodeGetMethodName, read at run time) has a row in the method tables of
// docs/user_guide.md and docs/api.md with the order and the stability limit the library computes,
// no row names a set the library does not know, and no documentation file holds a control
// character (a LaTeX command whose backslash was taken for an escape: \t of \text, \f of \frac,
// \b of \beta; or a real tab).
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The table row whose first cell begins with `name` ("" if there is none).
std::string RowOf(const std::vector<std::string>& lines, const std::string& name) {
  const std::string key = "| `" + name + "`";
  for (const std::string& line : lines) {
    if (line.compare(0, key.size(), key) == 0) return line;
  }
  return "";
}

struct SetFigures {
  std::string name;
  std::string orders;  // "x / x'": the global order in x' is capped by the one in x
  std::string limit;   // Omega_max to three decimals, "0 (" when weakly unstable for every h
};

std::vector<SetFigures> LibrarySets() {
  std::vector<SetFigures> sets;
  for (int i = 0; i < CEodeGetNumMethods(); ++i) {
    SetFigures s;
    s.name = CEodeGetMethodName(i);
    int degree = 0;
    sunrealtype params[8];
    EXPECT_EQ(CEodeGetMethodParams(s.name.c_str(), &degree, params, 8), CE_SUCCESS) << s.name;
    int ox = 0, ov = 0;
    EXPECT_EQ(CEodeMethodOrder(degree, params, &ox, &ov), CE_SUCCESS) << s.name;
    s.orders = std::to_string(ox) + " / " + std::to_string(std::min(ox, ov));
    sunrealtype limit = -1;
    EXPECT_EQ(CEodeStabilityLimit(degree, params, 0.0, &limit), CE_SUCCESS) << s.name;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", static_cast<double>(limit));
    s.limit = limit == 0 ? "0 (" : buf;
    sets.push_back(s);
  }
  return sets;
}

void ExpectEverySetDocumented(const char* doc) {
  const std::vector<std::string> lines = Lines(ReadFile(fs::path(CEODE_SOURCE_DIR) / doc));
  const std::vector<SetFigures> sets = LibrarySets();
  ASSERT_GE(sets.size(), 14u) << "the library lists fewer sets than the 14 it has had";
  std::set<std::string> known;
  for (const SetFigures& s : sets) {
    known.insert(s.name);
    const std::string row = RowOf(lines, s.name);
    ASSERT_FALSE(row.empty()) << doc << " has no table row for the named set " << s.name;
    EXPECT_NE(row.find("| " + s.orders + " |"), std::string::npos)
        << doc << ": the row of " << s.name << " lacks its order " << s.orders << ":\n"
        << row;
    EXPECT_NE(row.find("| " + s.limit), std::string::npos)
        << doc << ": the row of " << s.name << " lacks its Omega_max " << s.limit << ":\n"
        << row;
  }
  for (const std::string& line : lines) {
    if (line.compare(0, 4, "| `G") != 0) continue;
    const std::string name = line.substr(3, line.find('`', 3) - 3);
    EXPECT_EQ(known.count(name), 1u) << doc << " has a row for " << name << ", not a named set";
  }
}

TEST(Documentation, TheUserGuideGivesEveryNamedSetItsOrderAndStabilityLimit) {
  ExpectEverySetDocumented("docs/user_guide.md");
}

TEST(Documentation, TheApiReferenceGivesEveryNamedSetItsOrderAndStabilityLimit) {
  ExpectEverySetDocumented("docs/api.md");
}

// Newline is the only control character allowed (no tabs either: Markdown renders them unevenly).
TEST(Documentation, HasNoControlCharacters) {
  std::vector<fs::path> files = {fs::path(CEODE_SOURCE_DIR) / "README.md",
                                 fs::path(CEODE_SOURCE_DIR) / "CHANGELOG.md"};
  for (const auto& entry : fs::directory_iterator(fs::path(CEODE_SOURCE_DIR) / "docs")) {
    if (entry.path().extension() == ".md") files.push_back(entry.path());
  }
  ASSERT_GE(files.size(), 8u);
  for (const fs::path& file : files) {
    const std::vector<std::string> lines = Lines(ReadFile(file));
    ASSERT_FALSE(lines.empty()) << file;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      for (std::size_t col = 0; col < lines[i].size(); ++col) {
        const unsigned char c = static_cast<unsigned char>(lines[i][col]);
        EXPECT_FALSE(c < 0x20 || c == 0x7f)
            << file.string() << ":" << i + 1 << ":" << col + 1 << ": control character 0x"
            << std::hex << static_cast<int>(c) << std::dec << " in: " << lines[i];
      }
    }
  }
}

}  // namespace
