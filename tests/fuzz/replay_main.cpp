// SPDX-License-Identifier: MIT
// Runs a fuzz harness's LLVMFuzzerTestOneInput once on every file in the given files and folders
// (recursively, in sorted order), as a libFuzzer binary does with file arguments. Used in builds
// without libFuzzer, so the seed corpus and the saved crash inputs are part of the test suite
// (and of the sanitizer build). A missing folder is skipped with a message.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path path = argv[i];
    if (fs::is_directory(path)) {
      for (const auto& entry : fs::recursive_directory_iterator(path)) {
        if (entry.is_regular_file()) inputs.push_back(entry.path());
      }
    } else if (fs::is_regular_file(path)) {
      inputs.push_back(path);
    } else {
      std::printf("replay: %s does not exist, skipped\n", path.c_str());
    }
  }
  std::sort(inputs.begin(), inputs.end());
  for (const fs::path& input : inputs) {
    std::ifstream stream(input, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(stream),
                            std::istreambuf_iterator<char>()};
    std::printf("replay: %s (%zu bytes)\n", input.c_str(), bytes.size());
    std::fflush(stdout);  // the last line names the input if it crashes
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  }
  if (inputs.empty()) {
    std::printf("replay: no input found (expected the seed corpus)\n");
    return 1;
  }
  std::printf("replay: %zu inputs ran without a failure\n", inputs.size());
  return 0;
}
