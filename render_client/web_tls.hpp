// --web's tls=: the TLS context of the --web server (https and wss), from a PEM certificate and key
// or, for "self-signed", a fresh P-256 key and a certificate for localhost made at start (its
// SHA-256 fingerprint is printed, for the user to compare with what the browser shows).
#pragma once
#include <string>

#include <boost/asio/ssl/context.hpp>

namespace occ {

// spec: "CERT.pem:KEY.pem" or "self-signed". Throws InputError naming --web's tls= and the file.
boost::asio::ssl::context make_tls_context(const std::string& spec);

}  // namespace occ
