#pragma once
// Small text-file helpers shared by the readers and writers of output folders.
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rubdyn {

/// A file could not be written (the message names it): the CLI exits 5.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Splits one CSV line (RFC 4180 quoting: "a,b" is one field, "" inside quotes is a quote; a
/// trailing \r is dropped).
std::vector<std::string> split_csv_line(const std::string& line);

/// `text` as a double-quoted string that is both a TOML basic string and a JSON string: quote,
/// backslash, newline, tab and carriage return escaped with a backslash, every other control
/// character (and DEL) as a \u00XX escape, any other byte as is.
std::string quoted_string(std::string_view text);

/// Whether `text` is valid UTF-8 (no stray continuation byte, no truncated or overlong
/// sequence, no surrogate, nothing above U+10FFFF).
bool valid_utf8(std::string_view text);

/// `text` as it can be shown in a message: valid UTF-8 kept, every other byte, control
/// character and DEL as \xHH (a Latin-1 byte 0xB5 as \xB5, never the raw byte); at most
/// `max_chars` characters, then "..." (a long field does not flood the message).
std::string printable_text(std::string_view text, std::size_t max_chars = 80);

/// An input file that rubdyn refuses to read, with the reason (the caller names the file and
/// turns it into its own error: a case error, a matrix-file error).
class InputRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads a whole input file (a case, a matrix) of at most max_bytes. It is opened without
/// waiting (O_NONBLOCK: a FIFO without a writer would block the open) and asked what it is
/// before a byte is read. A regular file is read as large as it is (no buffer of max_bytes is
/// allocated); it may still grow while read, so at most max_bytes + 1 bytes are read. A FIFO (a
/// named pipe, or a shell's process substitution `rubdyn check <(gen-case)`) is read to its end,
/// waiting at most input_pipe_wait() seconds in all for its writer. Throws InputRefused with
/// the reason, which names the file's `role` ("case", "matrix"): cannot be opened or read, a
/// directory, a socket, a device (a FIFO or a device may never end, or never begin), a FIFO
/// from which nothing (or not all) arrived in time, larger than max_bytes.
std::string read_input_file(const std::string& path, std::size_t max_bytes, std::string_view role);

/// How long read_input_file waits for a FIFO's writer, in seconds: 10, or the environment
/// variable RUBDYN_PIPE_WAIT (0.01 to 3600) read once.
double input_pipe_wait();

/// rubdyn ends every row it writes with a line end: a last row without one was cut by a kill
/// (or a full disk) and may hold a truncated number. Readers drop it with this warning.
std::string cut_row_warning(const std::string& file, long line);

/// An output path that rubdyn refuses to write (a directory, a block device, a link to nothing,
/// a FIFO without a reader, an empty path): nothing was written, the CLI exits 2.
class PathRefused : public OutputError {
 public:
  using OutputError::OutputError;
};

// The one place where rubdyn opens a path for writing (README.md, "Output paths"). What is done
// depends on what the path is when it is opened:
//  - nothing, or a regular file: a whole file (write_file_atomic) is written to PATH.tmp and
//    renamed onto PATH, so that a reader never sees half of it; a stream (open_output_stream) is
//    created or truncated;
//  - the file the standard output goes to (/dev/stdout, /proc/self/fd/1, or the file stdout is
//    redirected to): written to the standard output, after what is already printed there;
//  - a symbolic link: never replaced; the file it points to is written through (as below for a
//    device, FIFO or socket; a regular file is truncated and rewritten in place, not atomically);
//    a link to nothing is refused;
//  - a character device, FIFO or socket: written through, never replaced or created; a FIFO
//    without a reader is refused (PathRefused) instead of waited for;
//  - a directory or a block device: refused (PathRefused).
// Every step is checked (open, write, close, rename); a failure throws OutputError naming the
// path ("cannot write PATH: reason"). `dir_fd` (an open directory, or AT_FDCWD) is the folder
// `name` is relative to, so that an output folder's files go into the folder the run holds
// open even if its path is moved; `shown` is the path named in messages.

/// Writes `text` to `path` by the rule above.
void write_file_atomic(const std::string& path, const std::string& text);
/// The same, `name` relative to the open directory `dir_fd`.
void write_file_at(int dir_fd, const std::string& name, const std::string& shown,
                   const std::string& text);
/// Opens `name` (relative to `dir_fd`) for streamed writing by the rule above; never null.
std::FILE* open_output_stream_at(int dir_fd, const std::string& name, const std::string& shown);
/// Throws PathRefused when `path` would be refused by the rule above (checked before any work
/// whose result goes there; a FIFO's reader is only checked when it is opened).
void check_output_path(const std::string& path);

}  // namespace rubdyn
