#include "json_list_stream.hpp"

#include <optional>

#include "json_node.hpp"
#include "mbsflow/error.hpp"

namespace mbsflow {
namespace {

// Builds one value from events: containers are opened and closed, values land in the
// innermost open one (under the last key read, for an object).
struct TreeBuilder {
  nlohmann::json value;
  std::vector<nlohmann::json*> open;
  std::string key;

  nlohmann::json* add(nlohmann::json&& v) {
    if (open.empty()) {
      value = std::move(v);
      return &value;
    }
    nlohmann::json& parent = *open.back();
    if (parent.is_array()) {
      parent.push_back(std::move(v));
      return &parent.back();
    }
    nlohmann::json& slot = parent[key];
    slot = std::move(v);
    return &slot;
  }
  void start(nlohmann::json&& container) { open.push_back(add(std::move(container))); }
};

class ListStream final : public JsonEvents {
 public:
  ListStream(const std::string& name, const JsonListHandlers& h) : name_(name), h_(h), seen_(h.lists.size(), false) {}

  nlohmann::json take_document() { return std::move(doc_.value); }

  bool null() override { return scalar(nullptr); }
  bool boolean(bool v) override { return scalar(v); }
  bool number_integer(number_integer_t v) override { return scalar(v); }
  bool number_unsigned(number_unsigned_t v) override { return scalar(v); }
  bool number_float(number_float_t v, const string_t&) override { return scalar(v); }
  bool string(string_t& v) override { return scalar(std::move(v)); }
  bool binary(binary_t& v) override { return scalar(nlohmann::json::binary(std::move(v))); }
  bool key(string_t& k) override {
    builder().key = std::move(k);
    return true;
  }
  bool start_object(std::size_t) override {
    builder().start(nlohmann::json::object());
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override {
    if (!list_ && doc_.open.size() == 1 && doc_.open.back()->is_object()) {
      for (std::size_t l = 0; l < h_.lists.size(); ++l) {
        if (h_.lists[l] != doc_.key) continue;
        if (seen_[l]) throw InputError(format_input_error(name_, {}, doc_.key, "given twice"));
        seen_[l] = true;
        doc_.add(nlohmann::json::array());
        list_ = l;
        count_ = 0;
        return true;
      }
    }
    builder().start(nlohmann::json::array());
    return true;
  }
  bool end_array() override {
    if (list_ && item_.open.empty()) {
      const std::size_t l = *list_;
      list_.reset();
      if (h_.end) h_.end(l, count_);
      return true;
    }
    return close();
  }

 private:
  TreeBuilder& builder() { return list_ ? item_ : doc_; }

  bool scalar(nlohmann::json&& v) {
    builder().add(std::move(v));
    if (list_ && item_.open.empty()) hand_over();
    return true;
  }
  bool close() {
    builder().open.pop_back();
    if (list_ && item_.open.empty()) hand_over();
    return true;
  }
  void hand_over() { h_.item(*list_, count_++, std::move(item_.value)); }

  const std::string& name_;
  const JsonListHandlers& h_;
  std::vector<bool> seen_;
  TreeBuilder doc_, item_;
  std::optional<std::size_t> list_;  // the streamed list being read
  std::size_t count_ = 0;
};

}  // namespace

nlohmann::json parse_json_streaming_lists(std::string_view text, const std::string& name, const JsonListHandlers& handlers) {
  ListStream stream(name, handlers);
  parse_json_events(text, name, stream);
  return stream.take_document();
}

}  // namespace mbsflow
