#include "rubdyn/io/case_error.hpp"

#include <fmt/format.h>

namespace rubdyn {

std::string format_issue(const CaseIssue& i) {
  const std::string where = i.line > 0 ? fmt::format("{}:{}", i.file, i.line) : i.file;
  if (i.value.empty()) return fmt::format("{}: {}: {}", where, i.key, i.rule);
  return fmt::format("{}: {} = {}: {}", where, i.key, i.value, i.rule);
}

static std::string join_issues(const std::vector<CaseIssue>& issues) {
  std::string s =
      fmt::format("invalid case: {} problem{}", issues.size(), issues.size() == 1 ? "" : "s");
  for (const auto& i : issues) s += "\n  " + format_issue(i);
  return s;
}

CaseError::CaseError(std::vector<CaseIssue> issues)
    : std::runtime_error(join_issues(issues)), issues_(std::move(issues)) {}

}  // namespace rubdyn
