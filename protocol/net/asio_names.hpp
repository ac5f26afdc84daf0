// The Boost.Asio names the transport and the link relay share (their .cpp files only: nothing
// of Boost.Asio reaches a header).
#pragma once
#include <chrono>
#include <utility>  // before asio: Boost 1.74 awaitable.hpp lacks it under C++20

#include <boost/asio.hpp>

namespace occ::asio_names {
namespace asio = boost::asio;
using tcp = asio::ip::tcp;
using boost::system::error_code;
using Clock = std::chrono::steady_clock;
}  // namespace occ::asio_names
