;;;; tools/soak.lisp -- make soak: a churning world for MINUTES of wall-clock time (default 5),
;;;; printing the heap after a full collection at every tenth of the run (#M9W5P7).

(load (merge-pathnames "boot.lisp" *load-truename*))

(in-package #:cl-user)

(when (luv-load-systems "luv-physics/workshop")
  (sb-ext:exit :code 2))

(let* ((text (uiop:getenv "MINUTES"))
       (minutes (if (and text (string/= text "")) (read-from-string text) 5)))
  (format t "make soak MINUTES=~A~%~%" minutes)
  (let ((growth (funcall (find-symbol "RUN-PHYSICS-SOAK" '#:luv-physics) :minutes minutes)))
    (format t "~%heap growth from the second row to the last: ~,2F MB~%" (/ growth 1048576.0))))
