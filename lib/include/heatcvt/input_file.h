#pragma once
/// \file input_file.h
/// The check every reader makes on an input path before opening it.
#include <string>

namespace heatcvt {

/// Throws IOError("<path>: <problem>") unless `path` names an existing regular file (through
/// symbolic links): a missing path, one that cannot be examined (a parent without permission),
/// a directory, or a FIFO, socket or device (opening a FIFO with no writer would block for ever;
/// /dev/zero never ends; a FIFO with a writer is refused too) each get their own message.
/// `what` names the kind of file in the messages ("file", "pose file").
void require_regular_file(const std::string& path, const std::string& what = "file");

}  // namespace heatcvt
