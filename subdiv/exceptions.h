// Exceptions shared by every room of prtsub. The CLI turns each into one line and a
// non-zero exit; the message already names the file or the stage that failed.
#pragma once

#include <stdexcept>
#include <string>

namespace prtsub {

//! Base class of every error prtsub reports.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

//! The input (a mesh, an asset, an option value) is malformed.
class InputError : public Error {
 public:
  using Error::Error;
};

//! A file could not be opened, read or written.
class IoError : public Error {
 public:
  using Error::Error;
};

//! Embree reported an error (device creation, scene build, out of memory).
class EmbreeError : public Error {
 public:
  using Error::Error;
};

//! A numerical solve failed (factorisation, singular system without fallback).
class SolverError : public Error {
 public:
  using Error::Error;
};

}  // namespace prtsub
