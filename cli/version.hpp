#pragma once

namespace rise::cli {

/// The build's version: the project version and `git describe --tags
/// --always --dirty` of the source tree, "0.1.0 (f28b7cb-dirty)", or the
/// project version alone when built outside a git checkout (a tarball).
/// Written at every build by cmake/rise_version.cmake.
const char* version();

}  // namespace rise::cli
