#pragma once

// What the fuzz targets share: a failed check names itself and its place
// before it aborts (libFuzzer reports the abort and keeps the input), and
// the seeds a target writes itself go into every corpus folder on its
// command line (from LLVMFuzzerInitialize).

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#define fuzz_check(ok)                                                                     \
  do {                                                                                     \
    if (!(ok)) {                                                                           \
      std::fprintf(stderr, "check failed: %s (%s:%d)\n", #ok, __FILE__, __LINE__);         \
      std::abort();                                                                        \
    }                                                                                      \
  } while (false)

namespace rise::fuzz {

/// Calls write(dir) for every argument that is a folder (libFuzzer's corpus).
template <typename Write>
void for_each_corpus_folder(int argc, char** argv, Write write) {
  for (int i = 1; i < argc; ++i) {
    struct stat st{};
    const std::string dir = argv[i];
    if (dir.empty() || dir[0] == '-' || ::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) continue;
    write(dir);
  }
}

}  // namespace rise::fuzz
