;;;; tools/boot.lisp -- put this repository on ASDF's search path; load systems or say why not.
;;;;
;;;; Loaded by tests/run.lisp, tools/check-anchors.lisp and tools/demo.lisp.
;;;; Compiled files go to ASDF's cache (~/.cache/common-lisp/...), never into the repository.

(require :asdf)

(in-package #:cl-user)

(defparameter *luv-root*
  (uiop:pathname-parent-directory-pathname (uiop:pathname-directory-pathname *load-truename*))
  "The repository directory, the one holding luv-physics.asd.")

(pushnew *luv-root* asdf:*central-registry* :test #'equal)

(defun luv-load-systems (&rest systems)
  "Load SYSTEMS with ASDF.  Return NIL, or after printing one line saying what failed, the error."
  (let (current)
    (handler-case
        (let ((*compile-verbose* nil) (*compile-print* nil) (*load-verbose* nil))
          (dolist (system systems nil)
            (setf current system)
            ;; compiler notes are for the page's authors (make notes), not for every run
            (handler-bind ((sb-ext:compiler-note #'muffle-warning))
              (asdf:load-system system))))
      (error (e)
        (format *error-output* "~&error: system ~A did not load: ~A~%" current e)
        (finish-output *error-output*)
        e))))
