// When to load the scene again, as a pure state machine: a reload asked for while a load runs is not
// started beside it but once it finishes, and any number of such requests make one load, of the newest
// file. docs/SERVICE.md, "Reloads".
#pragma once

namespace ph {

class ReloadQueue {
 public:
  // A reload was asked for. True: start a load now; false: one runs, another follows when it finishes.
  bool request() {
    if (!loading_) return loading_ = true;
    again_ = true;
    return false;
  }
  // The running load finished. True: start the load asked for meanwhile now (the queue stays busy).
  bool finished() {
    loading_ = again_;
    again_ = false;
    return loading_;
  }
  bool loading() const { return loading_; }

 private:
  bool loading_ = false;
  bool again_ = false;
};

}  // namespace ph
