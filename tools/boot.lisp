;;;; tools/boot.lisp -- put this repository on ASDF's search path; load systems or say why not.
;;;;
;;;; Loaded by tests/run.lisp, tools/check-anchors.lisp, tools/demo.lisp and the other tools.
;;;; Compiled files go to ASDF's cache (~/.cache/common-lisp/...), never into the repository.
;;;; What the compiler prints while a system is compiled (its notes, style-warnings and the
;;;; files' timings) goes to report/compile.log, appended; the terminal gets one line per load
;;;; that compiled something, and every full WARNING, which also makes the load fail.

(require :asdf)

(in-package #:cl-user)

(defparameter *luv-root*
  (uiop:pathname-parent-directory-pathname (uiop:pathname-directory-pathname *load-truename*))
  "The repository directory, the one holding luv-physics.asd.")

(pushnew *luv-root* asdf:*central-registry* :test #'equal)

(defparameter *luv-compile-log* (merge-pathnames "report/compile.log" *luv-root*)
  "Where luv-load-systems appends what the compiler printed.")

(defun luv-full-warning-p (condition)
  "True for a WARNING that is neither a style-warning nor ASDF's report that a file had
style-warnings: a warning the compiler means."
  (and (typep condition 'warning)
       (not (typep condition 'style-warning))
       (not (typep condition 'uiop:compile-warned-warning))))

(defun luv-compiled-files (text)
  "The files TEXT, the compiler's output, says were compiled, as a list of strings: the repository's
relative to it (with the seconds, for those the system's :around-compile timed), then how many
files of other systems."
  (let ((files '()) (others 0))
    (with-input-from-string (in text)
      (loop for line = (read-line in nil) while line
            do (let ((at (search "; luv-physics: compiled " line)))
                 (cond (at (push (subseq line (+ at 24)) files))
                       ((eql 0 (search "; compiling file \"" line))
                        (let ((name (subseq line 18 (position #\" line :start 18))))
                          (if (uiop:subpathp (pathname name) *luv-root*)
                              (push (enough-namestring name *luv-root*) files)
                              (incf others))))))))
    (append (nreverse files)
            (and (plusp others) (list (format nil "~D file~:P of other systems" others))))))

(defun luv-load-systems (&rest systems)
  "Load SYSTEMS with ASDF.  Return NIL, or after printing one line saying what failed, the error.
The compiler's output goes to *luv-compile-log*; a full warning is also printed as it comes."
  (let ((current nil) (terminal *error-output*) (style 0) (full 0)
        (captured (make-string-output-stream)))
    (ensure-directories-exist *luv-compile-log*)
    (with-open-file (log *luv-compile-log* :direction :output :if-exists :append
                                           :if-does-not-exist :create :external-format :utf-8)
      (let ((result
              (handler-case
                  (let* ((out (make-broadcast-stream log captured))
                         (*standard-output* out) (*error-output* out)
                         (*compile-verbose* t) (*compile-print* nil) (*load-verbose* nil))
                    (format log "~&;;;; ~A: loading ~{~A~^, ~}~%"
                            (uiop:unix-namestring (or *load-truename* "lisp")) systems)
                    (dolist (system systems nil)
                      (setf current system)
                      (handler-bind ((sb-ext:compiler-note #'muffle-warning)
                                     (warning (lambda (w)
                                                (cond ((luv-full-warning-p w)
                                                       (incf full)
                                                       (format terminal "~&WARNING (~A): ~A~%"
                                                               (if *compile-file-truename*
                                                                   (enough-namestring *compile-file-truename* *luv-root*)
                                                                   system)
                                                               (substitute #\Space #\Newline (princ-to-string w)))
                                                       (finish-output terminal))
                                                      (t nil)))))
                        (asdf:load-system system))))
                (error (e)
                  (format terminal "~&error: system ~A did not load: ~A~%" current e)
                  (finish-output terminal)
                  e)))
            (text (get-output-stream-string captured)))
        ;; the style-warnings the compiler reported, not those signalled and let pass unseen
        (setf style (loop for at = (search "caught STYLE-WARNING" text) then (search "caught STYLE-WARNING" text :start2 (1+ at))
                          while at count t))
        (let ((files (luv-compiled-files text)))
          (when (or files (plusp style) (plusp full))
            (format terminal "~&compile: ~{~A~^, ~}; ~D style-warning~:P, ~D warning~:P; the compiler's ~
                              notes and warnings are in ~A~%"
                    (or files '("nothing")) style full (enough-namestring *luv-compile-log* *luv-root*))
            (finish-output terminal)))
        (if (and (null result) (plusp full))
            (progn (format terminal "~&error: ~{~A~^, ~} compiled with ~D full warning~:P~%" systems full)
                   (finish-output terminal)
                   (make-condition 'simple-error :format-control "full warnings"))
            result)))))
