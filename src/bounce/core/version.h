// The program's version and the source revision it was built from, for files' "software"
// fields and --version. The revision lives in one generated file (CMakeLists.txt), so a commit
// recompiles that file only.
#pragma once

namespace bounce {

const char* bounce_version();   ///< "0.1.0"
const char* bounce_revision();  ///< the short git hash, or "unknown"
/// "bounce 0.1.0 (abc1234)"
const char* bounce_software();

}  // namespace bounce
