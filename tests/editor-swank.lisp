;;;; tests/editor-swank.lisp -- the image tools/editor-test talks to: luv-physics loaded, swank listening.
;;;;
;;;; Environment: SWANK_LOADER (Debian's swank-loader.lisp), SWANK_PORT_FILE (where the port
;;;; swank listens on, on 127.0.0.1, is written).  Swank's compiled files go where Debian's
;;;; swank-loader puts them (ASDF's cache).  The process then sleeps until it is stopped.

(load (merge-pathnames "../tools/boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(load (sb-ext:posix-getenv "SWANK_LOADER"))
(let ((*compile-verbose* nil) (*compile-print* nil) (*load-verbose* nil))
  (handler-bind ((warning #'muffle-warning))
    ;; swank itself, without its contribs (the checks use none) and without init files
    (funcall (find-symbol "INIT" "SWANK-LOADER") :setup nil)
    (funcall (find-symbol "INIT" "SWANK"))))
(setf (symbol-value (find-symbol "*LOOPBACK-INTERFACE*" "SWANK")) "127.0.0.1"
      (symbol-value (find-symbol "*LOG-EVENTS*" "SWANK")) nil)
(funcall (find-symbol "START-SERVER" "SWANK") (sb-ext:posix-getenv "SWANK_PORT_FILE") :dont-close t)
(loop (sleep 3600))
