;;;; tools/splice.lisp -- write a command's output into physics.org as a named example block.
;;;; Usage: sbcl --script tools/splice.lisp NAME FILE
;;;; The block '#+name: NAME' followed by '#+begin_example' ... '#+end_example' gets FILE's text.
;;;; Figures on the page are produced this way, by Makefile targets, never typed in.

(defun lines-of (path)
  (with-open-file (s path) (loop for line = (read-line s nil) while line collect line)))

(let* ((args (cdr sb-ext:*posix-argv*))
       (name (first args)) (file (second args))
       (page "physics.org"))
  (unless (and name file (probe-file file) (probe-file page))
    (format *error-output* "splice: usage: splice.lisp NAME FILE (run from the repository; FILE must exist)~%")
    (sb-ext:exit :code 2))
  (let* ((lines (lines-of page))
         (at (position (format nil "#+name: ~A" name) lines :test #'string-equal)))
    (unless (and at (< (1+ at) (length lines))
                 (string-equal (string-trim " " (nth (1+ at) lines)) "#+begin_example"))
      (format *error-output* "splice: physics.org has no '#+name: ~A' followed by #+begin_example~%" name)
      (sb-ext:exit :code 1))
    (let ((end (position "#+end_example" lines :start (+ at 2) :test #'string-equal
                                                :key (lambda (l) (string-trim " " l)))))
      (unless end
        (format *error-output* "splice: the example block ~A is not terminated~%" name)
        (sb-ext:exit :code 1))
      (with-open-file (out page :direction :output :if-exists :supersede)
        (dolist (l (subseq lines 0 (+ at 2))) (write-line l out))
        (dolist (l (lines-of file)) (write-line l out))
        (dolist (l (subseq lines end)) (write-line l out)))
      (format t "~&splice: wrote ~A into physics.org (~A)~%" file name))))
