# libzmq (libzmq3-dev) as the imported target mbsflow_zmq: its header and library only.
# Not pkg_check_modules(IMPORTED_TARGET): the cflags of libzmq's private requirements
# (-isystem /usr/include/mit-krb5) land in INCLUDES on the first configure and in FLAGS on
# the next, so a second configure recompiled everything that includes ZeroMQ.
if(NOT TARGET mbsflow_zmq)
  find_path(ZMQ_INCLUDE_DIR zmq.h REQUIRED)
  find_library(ZMQ_LIBRARY zmq REQUIRED)
  add_library(mbsflow_zmq UNKNOWN IMPORTED)
  set_target_properties(mbsflow_zmq PROPERTIES IMPORTED_LOCATION "${ZMQ_LIBRARY}"
                                               INTERFACE_INCLUDE_DIRECTORIES "${ZMQ_INCLUDE_DIR}")
endif()
