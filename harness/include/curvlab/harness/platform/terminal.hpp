// Whether stderr is a terminal that redraws a line in place (the session's
// progress bar, the preview's status line). POSIX: isatty; Windows: a
// console handle (GetConsoleMode), since MinTTY and redirections are pipes.
#pragma once

namespace curvlab::harness::platform {

bool stderr_is_terminal();

}  // namespace curvlab::harness::platform
