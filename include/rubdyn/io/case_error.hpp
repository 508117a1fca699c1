#pragma once
// Bad input: ONE error that lists every violated rule, each naming file, line, key, value and rule.
#include <stdexcept>
#include <string>
#include <vector>

namespace rubdyn {

struct CaseIssue {
  std::string file;   ///< case file path, or "--set" for a command-line override
  int line = 0;       ///< 1-based line in the file (0 when not applicable)
  std::string key;    ///< "section.key"
  std::string value;  ///< the offending value as written (empty when missing)
  std::string rule;   ///< the rule it breaks
};

class CaseError : public std::runtime_error {
 public:
  explicit CaseError(std::vector<CaseIssue> issues);
  const std::vector<CaseIssue>& issues() const { return issues_; }

 private:
  std::vector<CaseIssue> issues_;
};

/// "file:line: key = value: rule" for one issue.
std::string format_issue(const CaseIssue& i);

}  // namespace rubdyn
