// The processes a run's work is shared by, as the solvers see them: this process's rank, their
// number, and the collective operations between them (every process calls each in the same order).
// The solvers call a Communicator and never ask whether there is more than one process: with one,
// the serial one, every operation gives back this process's own values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace mesopen::parallel {

class Communicator {
public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // Every process's `mine`, concatenated in rank order.
  virtual std::vector<double> allGather(std::vector<double> mine) const = 0;
  virtual std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine) const = 0;
  // The same when every process knows how many values each gives (`sizes[r]` from process r): no
  // sizes are gathered first.
  virtual std::vector<double> allGather(std::vector<double> mine,
                                        const std::vector<std::int64_t> &sizes) const = 0;
  virtual std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine,
                                              const std::vector<std::int64_t> &sizes) const = 0;
  // Every process's `mine` (as many values on every process) summed element by element, the
  // processes' values added in rank order (the same sums on every process, whatever the message
  // order); one process: `mine` as it is.
  virtual std::vector<double> sumInOrder(std::vector<double> mine) const = 0;
  // The smallest of every process's `value` (std::min taken in rank order).
  virtual double min(double value) const = 0;
  // The largest of every process's `values`, element by element (exact in any order).
  virtual std::vector<double> max(std::vector<double> values) const = 0;
  // Values each process holds part of, copied to every process: `pack` writes this process's
  // `count` values, `unpack` reads every process's, concatenated in rank order. One process holds
  // them all already: neither is called.
  virtual void share(std::size_t count, const std::function<void(double *)> &pack,
                     const std::function<void(const double *)> &unpack) const = 0;
  // The same to process 0 alone (what it writes), process by process: there, `unpack(r, values)`
  // is called for each other process r in rank order with its values, so that no process ever
  // holds every process's at once (process 0's own are where they were).
  virtual void collect(std::size_t count, const std::function<void(double *)> &pack,
                       const std::function<void(int, const double *)> &unpack) const = 0;
  // Values for some processes only: `to[r]` goes to process r (one list per process, this one's
  // own included); returns the lists every process sent this one, by sender rank. Each list, an
  // empty one too, is a message with its length: no collective call, P - 1 messages each way.
  virtual std::vector<std::vector<std::int64_t>>
  exchange(std::vector<std::vector<std::int64_t>> to) const = 0;
  // The same with the processes `partners` alone (ascending, this one not among them; each
  // partner has this one among its own): a message to and from each of them, an empty list too;
  // the lists to the others must be empty, those from them are.
  virtual std::vector<std::vector<std::int64_t>>
  exchangeWith(std::vector<std::vector<std::int64_t>> to,
               const std::vector<int> &partners) const = 0;
  // The same when this process knows how many values each will send it (`sizes[r]` from process
  // r, its own list's included): no sizes are exchanged first.
  virtual std::vector<std::vector<std::int64_t>>
  exchange(std::vector<std::vector<std::int64_t>> to,
           const std::vector<std::int64_t> &sizes) const = 0;
};

// One process: gathers and reductions give back their input.
class SerialCommunicator final : public Communicator {
public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::vector<double> allGather(std::vector<double> mine) const override { return mine; }
  std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine) const override {
    return mine;
  }
  std::vector<double> allGather(std::vector<double> mine,
                                const std::vector<std::int64_t> &) const override {
    return mine;
  }
  std::vector<std::int64_t> allGather(std::vector<std::int64_t> mine,
                                      const std::vector<std::int64_t> &) const override {
    return mine;
  }
  std::vector<double> sumInOrder(std::vector<double> mine) const override { return mine; }
  double min(double value) const override { return value; }
  std::vector<double> max(std::vector<double> values) const override { return values; }
  void share(std::size_t, const std::function<void(double *)> &,
             const std::function<void(const double *)> &) const override {}
  void collect(std::size_t, const std::function<void(double *)> &,
               const std::function<void(int, const double *)> &) const override {}
  std::vector<std::vector<std::int64_t>>
  exchange(std::vector<std::vector<std::int64_t>> to) const override {
    return to;
  }
  std::vector<std::vector<std::int64_t>> exchangeWith(std::vector<std::vector<std::int64_t>> to,
                                                      const std::vector<int> &) const override {
    return to;
  }
  std::vector<std::vector<std::int64_t>>
  exchange(std::vector<std::vector<std::int64_t>> to,
           const std::vector<std::int64_t> &) const override {
    return to;
  }
};

// The one serial communicator (a solver's default).
const Communicator &serial();

// Values of `items` that move between processes: item k's `count(k)` values go from process
// from(k) to process to(k), packed there (`pack(k, out)`) and unpacked at the receiver (`unpack(k,
// in)`), in item order. Every process knows every item's sender, receiver and count: messages
// alone (Communicator::exchange with the sizes given); an item whose processes are the same stays.
void moveValues(const Communicator &processes, std::size_t items,
                const std::function<int(std::size_t)> &from,
                const std::function<int(std::size_t)> &to,
                const std::function<std::size_t(std::size_t)> &count,
                const std::function<void(std::size_t, double *)> &pack,
                const std::function<void(std::size_t, const double *)> &unpack);

} // namespace mesopen::parallel
