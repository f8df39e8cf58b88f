#include "semantic/app/progress_bar.hpp"

#include <unistd.h>

#include <algorithm>

namespace rise::semantic {

std::string progress_line(std::size_t done, std::size_t total, std::string_view stage, int width) {
  done = std::min(done, total);
  const double fraction = total == 0 ? 0.0 : static_cast<double>(done) / static_cast<double>(total);
  const int cells = std::max(width, 1);
  const int filled = static_cast<int>(fraction * cells);
  std::string line(stage);
  if (line.size() < 18) line.resize(18, ' ');
  line += " [";
  line.append(static_cast<std::size_t>(filled), '#');
  line.append(static_cast<std::size_t>(cells - filled), '.');
  char tail[64];
  std::snprintf(tail, sizeof tail, "] %3d%%  %zu/%zu", static_cast<int>(fraction * 100.0), done, total);
  return line + tail;
}

ProgressBar::ProgressBar(std::FILE* out) : ProgressBar(out, out != nullptr && isatty(fileno(out)) == 1) {}

ProgressBar::ProgressBar(std::FILE* out, bool terminal) : out_(out), terminal_(terminal) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(std::size_t done, std::size_t total, std::string_view stage) {
  if (out_ == nullptr) return;
  if (!open_ || stage != stage_) {
    end_stage();
    stage_ = stage;
    open_ = true;
    drawn_percent_ = -1;
    stage_start_ = std::chrono::steady_clock::now();
  }
  done_ = done;
  total_ = total;
  if (!terminal_) return;  // the stage's one line comes when it ends
  const int percent = total == 0 ? 0 : static_cast<int>(100 * std::min(done, total) / total);
  if (percent == drawn_percent_) return;
  drawn_percent_ = percent;
  std::fprintf(out_, "\r%s", progress_line(done, total, stage_).c_str());
  std::fflush(out_);
}

void ProgressBar::finish() { end_stage(); }

void ProgressBar::end_stage() {
  if (!open_ || out_ == nullptr) return;
  open_ = false;
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start_).count();
  if (terminal_) {
    std::fprintf(out_, "\r%s  %.2f s\n", progress_line(done_, total_, stage_).c_str(), elapsed_s);
  } else {
    std::fprintf(out_, "%s: %zu/%zu  %.2f s\n", stage_.c_str(), std::min(done_, total_), total_, elapsed_s);
  }
  std::fflush(out_);
}

std::function<void(std::size_t, std::size_t, std::string_view)> ProgressBar::callback() {
  return [this](std::size_t done, std::size_t total, std::string_view stage) { update(done, total, stage); };
}

}  // namespace rise::semantic
