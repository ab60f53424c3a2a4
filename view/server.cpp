// SPDX-License-Identifier: MIT
#include "view/server.h"

#include <fmt/format.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>

#include "framework/error.h"

namespace harap::view {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;

namespace {

struct Asset {
  std::string content;
  std::string type;
};

// The page's files by URL path ("/index.html"). Only regular files under `root` are read;
// a request for anything else is a 404, so no request reaches the file system.
std::map<std::string, Asset> ReadAssets(const std::filesystem::path& root) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(root / "index.html", error)) {
    throw InputError(fmt::format(
        "the page's files are not in {} (no index.html): build the `harap_view_assets` target "
        "or install harap (cmake --install)",
        root.string()));
  }
  std::map<std::string, Asset> assets;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream file(entry.path(), std::ios::binary);
    std::ostringstream content;
    content << file.rdbuf();
    const std::string url = "/" + std::filesystem::relative(entry.path(), root).generic_string();
    assets[url] = Asset{content.str(), ContentType(entry.path())};
  }
  return assets;
}

}  // namespace

std::string ContentType(const std::filesystem::path& file) {
  static const std::map<std::string, std::string> kTypes = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".png", "image/png"},
      {".svg", "image/svg+xml"}};
  const auto it = kTypes.find(file.extension().string());
  return it == kTypes.end() ? "application/octet-stream" : it->second;
}

struct Server::Impl {
  const Registries& registries;
  const ViewSource& source;
  std::map<std::string, Asset> assets;
  bool stop_on_signals = true;
  net::io_context io{1};
  tcp::acceptor acceptor{io};
  // Worker threads still running (each holds its page); Run() waits for them.
  std::mutex workers_mutex;
  std::condition_variable workers_done;
  int workers = 0;
  // Ends each open page's worker (after its current message) when the server stops.
  std::vector<std::function<void()>> close_pages;

  Impl(const Registries& r, const ViewSource& s) : registries(r), source(s) {}
  void Accept();
};

namespace {

// One WebSocket page: reads on the network thread, solves on its worker thread.
class PageConnection : public std::enable_shared_from_this<PageConnection> {
 public:
  PageConnection(tcp::socket socket, Server::Impl& server)
      : ws_(std::move(socket)), server_(server) {}

  void Accept(http::request<http::string_body> request, const PageOptions& options) {
    options_ = options;
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    // The page's largest message is a few hundred bytes; a larger one closes the connection.
    ws_.read_message_max(1 << 20);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code error) {
      if (!error) self->Started();
    });
  }

 private:
  struct Inbox {
    std::mutex mutex;
    std::condition_variable ready;
    std::vector<std::string> texts;
    std::vector<size_t> binary_sizes;
    /// How many of `texts` supersede a full solve (SupersedesFullSolve): one stops it.
    size_t superseding = 0;
    bool closed = false;
  };

  void Started() {
    {
      std::lock_guard lock(server_.workers_mutex);
      ++server_.workers;
      server_.close_pages.push_back([weak = weak_from_this()] {
        if (const auto self = weak.lock()) self->Close();
      });
    }
    worker_ = std::thread([self = shared_from_this()] { self->Work(); });
    worker_.detach();
    Read();
  }

  void Read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code error, size_t) {
      if (error) {
        self->Close();
        return;
      }
      if (self->ws_.got_text()) {
        std::string text = beast::buffers_to_string(self->buffer_.data());
        const bool superseding = SupersedesFullSolve(text);
        std::lock_guard lock(self->inbox_.mutex);
        self->inbox_.texts.push_back(std::move(text));
        self->inbox_.superseding += superseding;
      } else {
        std::lock_guard lock(self->inbox_.mutex);
        self->inbox_.binary_sizes.push_back(self->buffer_.size());
      }
      self->inbox_.ready.notify_one();
      self->buffer_.consume(self->buffer_.size());
      self->Read();
    });
  }

  void Close() {
    {
      std::lock_guard lock(inbox_.mutex);
      inbox_.closed = true;
    }
    inbox_.ready.notify_one();
  }

  // The worker: the page's session lives and dies here.
  void Work() {
    {
      PageSession page(
          server_.registries, server_.source,
          [weak = weak_from_this(), this](Outgoing message) {
            net::post(ws_.get_executor(),
                      [self = weak.lock(), message = std::move(message)]() mutable {
                        if (self) self->Send(std::move(message));
                      });
          },
          options_,
          [this] {
            // Only a message that makes the solve pointless stops it: after an added handle
            // the solve would be resumed, and the two would share the cores with the page.
            std::lock_guard lock(inbox_.mutex);
            return inbox_.closed || inbox_.superseding > 0;
          });
      page.Start();
      for (;;) {
        std::vector<std::string> texts;
        std::vector<size_t> binary_sizes;
        {
          std::unique_lock lock(inbox_.mutex);
          inbox_.ready.wait(lock, [&] {
            return inbox_.closed || !inbox_.texts.empty() || !inbox_.binary_sizes.empty();
          });
          if (inbox_.closed) break;
          texts.swap(inbox_.texts);
          binary_sizes.swap(inbox_.binary_sizes);
          inbox_.superseding = 0;
        }
        for (const size_t size : binary_sizes) page.HandleBinary(size);
        if (!texts.empty()) page.HandleTexts(texts);
      }
    }
    std::lock_guard lock(server_.workers_mutex);
    --server_.workers;
    server_.workers_done.notify_all();
  }

  // On the network thread: queue the message and write the queue in order.
  void Send(Outgoing message) {
    outbox_.push_back(std::move(message));
    if (outbox_.size() == 1) WriteNext();
  }
  void WriteNext() {
    ws_.binary(outbox_.front().binary);
    ws_.async_write(net::buffer(outbox_.front().data),
                    [self = shared_from_this()](beast::error_code error, size_t) {
                      self->outbox_.pop_front();
                      if (error) {
                        self->outbox_.clear();
                        return;
                      }
                      if (!self->outbox_.empty()) self->WriteNext();
                    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  Server::Impl& server_;
  PageOptions options_;
  beast::flat_buffer buffer_;
  Inbox inbox_;
  std::thread worker_;
  std::deque<Outgoing> outbox_;
};

// One HTTP connection: files, or the upgrade to a page's WebSocket.
class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(tcp::socket socket, Server::Impl& server)
      : stream_(std::move(socket)), server_(server) {}

  void Read() {
    request_ = {};
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, request_,
                     [self = shared_from_this()](beast::error_code error, size_t) {
                       if (!error) self->Answer();
                     });
  }

 private:
  void Answer() {
    auto response = std::make_shared<http::response<http::string_body>>();
    response->version(request_.version());
    response->keep_alive(request_.keep_alive());
    response->set(http::field::server, "harap view");
    const std::string target(request_.target());
    std::string path = target.substr(0, target.find_first_of("?#"));
    if (websocket::is_upgrade(request_)) {
      // A refused upgrade is answered and the connection closed after the answer.
      response->keep_alive(false);
      response->set(http::field::content_type, "text/plain");
      if (path != "/ws") {
        response->result(http::status::not_found);
        response->body() = "the page's WebSocket is at /ws\n";
        Write(response);
        return;
      }
      std::string query;
      if (path.size() < target.size() && target[path.size()] == '?') {
        query = target.substr(path.size() + 1);
        query = query.substr(0, query.find('#'));
      }
      try {
        const PageOptions options = ParsePageQuery(query);
        stream_.expires_never();
        std::make_shared<PageConnection>(stream_.release_socket(), server_)
            ->Accept(std::move(request_), options);
        return;
      } catch (const InputError& error) {
        // Refused before the upgrade: the answer names the problem.
        response->result(http::status::bad_request);
        response->body() = std::string(error.what()) + "\n";
        Write(response);
        return;
      }
    }
    if (path == "/") path = "/index.html";
    const auto it = server_.assets.find(path);
    if (request_.method() != http::verb::get && request_.method() != http::verb::head) {
      response->result(http::status::method_not_allowed);
      response->set(http::field::content_type, "text/plain");
      response->body() = "only GET and HEAD\n";
    } else if (it == server_.assets.end()) {
      response->result(http::status::not_found);
      response->set(http::field::content_type, "text/plain");
      response->body() = "not one of the page's files\n";
    } else {
      response->result(http::status::ok);
      response->set(http::field::content_type, it->second.type);
      response->set(http::field::cache_control, "no-cache");
      if (request_.method() == http::verb::get) response->body() = it->second.content;
    }
    Write(response);
  }

  void Write(const std::shared_ptr<http::response<http::string_body>>& response) {
    response->prepare_payload();
    http::async_write(stream_, *response,
                      [self = shared_from_this(), response](beast::error_code error, size_t) {
                        if (error || !response->keep_alive()) {
                          beast::error_code ignored;
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                          return;
                        }
                        self->Read();
                      });
  }

  beast::tcp_stream stream_;
  Server::Impl& server_;
  beast::flat_buffer buffer_;
  http::request<http::string_body> request_;
};

}  // namespace

void Server::Impl::Accept() {
  acceptor.async_accept(io, [this](beast::error_code error, tcp::socket socket) {
    if (error) {
      if (error == net::error::operation_aborted) return;
    } else {
      // Without TCP_NODELAY a small message written right after another (a solve's JSON after
      // its positions frame) waits for the page's delayed acknowledgement of the first, up to
      // 40 ms on Linux (Nagle's algorithm): the page must get every frame as soon as it is out.
      beast::error_code ignored;
      socket.set_option(tcp::no_delay(true), ignored);
      std::make_shared<HttpConnection>(std::move(socket), *this)->Read();
    }
    Accept();
  });
}

Server::Server(const ServerOptions& options, const Registries& registries, const ViewSource& source)
    : impl_(std::make_unique<Impl>(registries, source)) {
  impl_->assets = ReadAssets(options.assets);
  impl_->stop_on_signals = options.stop_on_signals;
  beast::error_code error;
  const net::ip::address address = net::ip::make_address(options.host, error);
  if (error)
    throw InputError(
        fmt::format("--host {}: not an IP address ({})", options.host, error.message()));
  const tcp::endpoint endpoint(address, options.port);
  tcp::acceptor& acceptor = impl_->acceptor;
  acceptor.open(endpoint.protocol(), error);
  if (!error) acceptor.set_option(net::socket_base::reuse_address(true), error);
  if (!error) acceptor.bind(endpoint, error);
  if (!error) acceptor.listen(net::socket_base::max_listen_connections, error);
  if (error) {
    throw InputError(
        fmt::format("cannot listen on {}:{}: {}", options.host, options.port, error.message()));
  }
}

Server::~Server() = default;

uint16_t Server::port() const { return impl_->acceptor.local_endpoint().port(); }

void Server::Run() {
  std::optional<net::signal_set> signals;
  if (impl_->stop_on_signals) {
    signals.emplace(impl_->io, SIGINT, SIGTERM);
    signals->async_wait([this](beast::error_code error, int) {
      if (!error) Stop();
    });
  }
  impl_->Accept();
  impl_->io.run();
  std::unique_lock lock(impl_->workers_mutex);
  for (const auto& close : impl_->close_pages) close();
  impl_->workers_done.wait(lock, [&] { return impl_->workers == 0; });
}

void Server::Stop() {
  net::post(impl_->io, [this] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->io.stop();
  });
}

}  // namespace harap::view
