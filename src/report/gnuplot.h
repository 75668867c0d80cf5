#pragma once

// Running gnuplot safely: no shell, argv only, stdin closed, a timeout, the exit status checked,
// and every piece of text that reaches a script reduced to characters that cannot start a
// command substitution, a macro or a string escape.

#include <string>

#include "core/temp_dir.h"  // TempDir, for the scripts

namespace rotorid::internal {

// The executable for `name`: itself when it contains '/', else the first match on PATH. Empty
// when there is no such executable regular file.
std::string FindExecutable(const std::string& name);

// `text` as a single-quoted gnuplot string literal ('...'), keeping letters, digits, space and
// .,:;_+-=()[]/%<>#*|~ and replacing anything else (quotes, backquotes, @, $, \, newlines,
// non-ASCII) by '_'.
std::string GnuplotString(const std::string& text);

// A path as a single-quoted gnuplot string; throws rotorid::Error when it holds characters a
// gnuplot string cannot carry (newlines, quotes).
std::string GnuplotPath(const std::string& path);

struct ProcessResult {
  bool ok = false;         // exited normally with status 0
  int exit_code = -1;      // exit status, or 128 + signal
  bool timed_out = false;  // killed after the timeout
  std::string error_text;  // the end of gnuplot's stderr, or why it could not start
};

// Runs `executable --default-settings script` (no init files, so the user's ~/.gnuplot cannot
// change the figures) with stdin and stdout on /dev/null and stderr captured to `stderr_path`.
// Kills it after `timeout_s`.
ProcessResult RunGnuplotScript(const std::string& executable, const std::string& script_path,
                               const std::string& stderr_path, double timeout_s);

}  // namespace rotorid::internal
